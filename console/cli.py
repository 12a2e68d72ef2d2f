"""The console on the command line: `mavswarm replay PATH...`, and `--web` for `mavswarm up`
(the live view of the swarm it runs) and `mavswarm bench run` (the sessions it runs);
`mavswarm serve` gets the console under `/console`.

`add_parsers` adds `replay`; `extend_up`, `extend_serve` and `extend_bench` add `--web` to `up`
and `bench run` and the console to `serve`, commands defined by the packages below (the
composition root calls each after the command's own package added it).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import functools
import signal
import sys
import threading
from collections.abc import AsyncIterator, Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from console.frame_rate import DEFAULT_RATE_HZ, check_rate_hz
from emulator.capacity import MAX_VEHICLES_PER_NETWORK

if TYPE_CHECKING:  # the rest is imported by the commands that use it: `--help` stays quick
    from benchmark.authoring.session_folders import SessionFolders
    from benchmark.server import Hub
    from benchmark.server.link_routes import LinkTarget
    from benchmark.server.serve import ApiKey
    from console.app import ConsoleState
    from emulator.swarm import Swarm
    from mavlink_gateway import Gateway

__all__ = ["DEFAULT_HOST", "DEFAULT_PORT", "add_parsers", "console_for_hub", "extend_bench",
           "extend_serve", "extend_up", "run_replay", "swarm_console"]

DEFAULT_HOST = "127.0.0.1"
DEFAULT_PORT = 8765
SERVE_MOUNT = "/console"


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """`replay`, on the `mavswarm` command's subparsers."""
    replay = sub.add_parser(
        "replay", help="open recorded runs in the web console (truth files, results folders)",
        description="Serve the web console over a ground-truth file (*.truth.npz) or benchmark "
                    "results folders (replay, run inspector, comparison).")
    replay.add_argument("paths", type=Path, nargs="+", metavar="PATH",
                        help="a *.truth.npz file, a results folder, or a folder of them")
    replay.add_argument("--session", type=Path, help="a truth file's session (its world), "
                        "for truth files that carry none")
    replay.add_argument("--host", default=DEFAULT_HOST, help="address to listen on")
    replay.add_argument("--port", type=int, default=DEFAULT_PORT, help="TCP port")
    replay.add_argument("--key", help="require this key (default: none; the console "
                        "serves this machine's files on 127.0.0.1)")
    _add_session_dir_argument(replay)
    replay.set_defaults(run=run_replay)


def extend_up(sub: argparse._SubParsersAction) -> None:
    """`up --web`: the live view of the swarm."""
    up = sub.choices["up"]
    _add_web_arguments(up, "serve the web console's live view of the swarm (prints the URL)")
    _add_session_dir_argument(up)
    up.set_defaults(run=_run_up, run_up_next=up.get_default("run"))


def extend_serve(sub: argparse._SubParsersAction) -> None:
    """The console of `serve`, under /console."""
    serve = sub.choices["serve"]
    _add_session_dir_argument(serve)
    serve.set_defaults(extend=console_for_hub, run=_run_serve,
                       run_serve_next=serve.get_default("run"))


def extend_bench(sub: argparse._SubParsersAction) -> None:
    """`bench run --web`: the console following the sessions being run."""
    bench = sub.choices["bench"]
    bench_sub = next(a for a in bench._actions if isinstance(a, argparse._SubParsersAction))
    run = bench_sub.choices["run"]
    _add_web_arguments(run, "follow the sessions being run in the web console (prints the URL); "
                            "it stays open after the run until Ctrl-C")
    run.add_argument("--web-exit", action="store_true",
                     help="--web: close the console and exit when the run ends")
    bench.set_defaults(run=_run_bench, run_bench_next=bench.get_default("run"))


def _add_web_arguments(parser: argparse.ArgumentParser, what: str) -> None:
    parser.add_argument("--web", action="store_true", help=what)
    parser.add_argument("--web-host", default=DEFAULT_HOST, help="--web: address to listen on")
    parser.add_argument("--web-port", type=int, default=DEFAULT_PORT, help="--web: TCP port")
    parser.add_argument("--web-key", help="--web: the operator key (default: generated)")
    parser.add_argument("--web-hz", type=_rate_hz, default=DEFAULT_RATE_HZ,
                        help="--web: live updates per second (0.5 to 60)")


def _rate_hz(text: str) -> float:
    try:
        return check_rate_hz(float(text))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a rate from 0.5 to 60 Hz") from None


def _session_dir(text: str) -> Path:
    path = Path(text)
    if not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is not a folder")
    return path


def _add_session_dir_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--session-dir", dest="session_dirs", type=_session_dir,
                        action="append", default=[], metavar="DIR",
                        help="a folder whose session files may be opened by path (the "
                             "editor, POST /sessions/load), besides benchmark/sessions, the "
                             "editor's save folder and the files served (repeatable)")


def _folders(dirs: Sequence[Path], files: Sequence[Path] = ()) -> SessionFolders:
    from benchmark.authoring.session_folders import SessionFolders
    folders = SessionFolders(files=files)
    for folder in dirs:
        folders.allow_folder(folder)
    return folders


def _print(text: str) -> None:
    """Print a console URL; where the page is not built, say so (once) and how to build it."""
    from console.bundle import bundle_problem
    print(text, flush=True)
    problem = bundle_problem()
    if problem is not None and not _warned:
        _warned.append(problem)
        print(f"mavswarm: {problem}", file=sys.stderr, flush=True)


_warned: list[str] = []


@contextlib.asynccontextmanager
async def swarm_console(swarm: Swarm, *, host: str = DEFAULT_HOST, port: int = DEFAULT_PORT,
                        key: str | None = None, rate_hz: float = DEFAULT_RATE_HZ,
                        on_ready: Callable[[str, str], None] | None = None,
                        session_folders: SessionFolders | None = None
                        ) -> AsyncIterator[ConsoleState]:
    """The console's live view of `swarm` served while inside; `on_ready(url, key)`;
    `session_folders`: where the editor opens session files (default: the shipped suite;
    its save folder is added)."""
    from benchmark.authoring.session_folders import SessionFolders
    from benchmark.server.link_routes import LinkTarget
    from benchmark.server.serve import serve_asgi
    from console.app import ConsoleState, create_console_app
    from console.auth import ConsoleAuth
    from console.commands import Commander
    from console.live import LiveSwarm
    from emulator.scenario_export import scenario_to_dict
    from emulator.services import SwarmServices
    from mavlink_gateway import FleetConnection, Gateway, profiles_from_scenario
    auth, key = ConsoleAuth.single_key(key)
    scenario = swarm.fleet.scenario
    gateway_stack = contextlib.AsyncExitStack()

    async def open_gateway() -> Gateway:
        _, bound = swarm.endpoints[0].local_address
        fleet = await FleetConnection.connect(
            f"udpout://127.0.0.1:{bound}", profiles_from_scenario(scenario),
            scenario.world.origin)
        gateway_stack.push_async_callback(fleet.close)
        return Gateway(fleet.drones, SwarmServices(swarm))

    commander = None if swarm.ports.per_vehicle else Commander("swarm", open_gateway)
    link_target = LinkTarget(SwarmServices(swarm))
    live = LiveSwarm("swarm", scenario.name, scenario_to_dict(scenario), swarm,
                     commander=commander, links=lambda _role: link_target)
    state = ConsoleState(auth, {"swarm": live}, rate_hz=rate_hz,
                         session_folders=session_folders or SessionFolders())
    app = create_console_app(state)

    listening = asyncio.Event()

    def ready(url: str) -> None:
        listening.set()
        if on_ready is not None:
            on_ready(url, key)

    server = asyncio.create_task(serve_asgi(app, host=host, port=port, on_ready=ready))
    try:
        # A port that cannot be listened on ends the command (the error), not just the page.
        started = asyncio.create_task(listening.wait())
        await asyncio.wait({server, started}, return_when=asyncio.FIRST_COMPLETED)
        started.cancel()
        if server.done():
            server.result()
        yield state
    finally:
        server.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await server
        await state.aclose()
        if commander is not None:
            await commander.aclose()
        await gateway_stack.aclose()


def _run_up(args: argparse.Namespace) -> int:
    if args.web:
        most = MAX_VEHICLES_PER_NETWORK
        if args.session is None and (args.drones or 0) > most:
            print(f"mavswarm: --web shows one swarm of at most {most} drones; {args.drones} "
                  "run as several networks", file=sys.stderr)
            return 2

        def attach(swarm: Swarm, _network: int | None
                   ) -> contextlib.AbstractAsyncContextManager[object]:
            return swarm_console(
                swarm, host=args.web_host, port=args.web_port, key=args.web_key,
                rate_hz=args.web_hz, session_folders=_folders(
                    args.session_dirs, [args.session] if args.session else []),
                on_ready=lambda url, key: _print(f"web console: {url}/live/swarm?key={key}"))
        args.attachments = [*getattr(args, "attachments", ()), attach]
    return args.run_up_next(args)


def _run_bench(args: argparse.Namespace) -> int:
    if args.bench_command != "run" or not args.web:
        return int(args.run_bench_next(args))
    # Only here: the console's app (its editor, the oracle, scipy) is a third of a second of
    # start-up that every other `bench` command would pay.
    from console.bench_watch import LiveBoard, serve_in_thread
    board = LiveBoard()
    try:
        with serve_in_thread(board, host=args.web_host, port=args.web_port, key=args.web_key,
                             rate_hz=args.web_hz) as (url, key):
            _print(f"web console: {url}/?key={key} (pick the session to follow)")
            args.live_hz, args.on_live = args.web_hz, board.update
            status = int(args.run_bench_next(args))
            if args.web_exit or status in (2, 130):  # asked to, bad input, or interrupted
                return status
            _print(f"the run is over; the web console stays open at {url}/?key={key} until "
                   "Ctrl-C (--web-exit: exit when the run ends)")
            _wait_for_interrupt()
            return status
    except OSError as error:
        print(f"mavswarm: {error}", file=sys.stderr)
        return 2


def _run_serve(args: argparse.Namespace) -> int:
    args.extend = functools.partial(console_for_hub, session_dirs=args.session_dirs)
    return int(args.run_serve_next(args))


def _wait_for_interrupt() -> None:
    """Block until Ctrl-C (SIGINT) or SIGTERM."""
    stop = threading.Event()
    previous = signal.signal(signal.SIGTERM, lambda *_: stop.set())
    try:
        while not stop.wait(0.5):
            pass
    except KeyboardInterrupt:
        pass
    finally:
        signal.signal(signal.SIGTERM, previous)


def console_for_hub(app: Any, hub: Hub, keys: Sequence[ApiKey],
                    session_dirs: Sequence[Path] = ()) -> Callable[[str], None]:
    """Mount the console on `serve`'s app at /console: operator and admin keys of the hub open
    it, agent keys are refused. Sessions loaded later appear as they start. The editor and
    `POST /sessions/load` share the hub's session folders, `session_dirs` added."""
    from benchmark.running.replay_data import session_world
    from benchmark.server.link_routes import session_link_target
    from benchmark.server.operator_rule import served_refusal
    from console.app import ConsoleState, create_console_app
    from console.auth import ConsoleAuth
    from console.commands import Commander
    from console.live import LiveSwarm
    for folder in session_dirs:
        hub.session_folders.allow_folder(folder)

    def lookup(key: str) -> str | None:
        caller = hub.caller(key)
        return None if caller is None else caller.role.value

    state = ConsoleState(ConsoleAuth(lookup), session_folders=hub.session_folders)
    commanders: dict[str, Commander] = {}

    def sync() -> None:
        for sid, session in hub.sessions.items():
            if sid in state.lives:
                continue
            commanders[sid] = Commander(sid, session.gateway, refusal=functools.partial(
                served_refusal, hub, sid, "flight commands from the console"))

            def activity(sid: str = sid) -> dict[str, dict[str, Any]]:
                tools = hub.sessions[sid].tools
                return tools.activity() if hasattr(tools, "activity") else {}

            def links(role: str, sid: str = sid) -> LinkTarget:
                return session_link_target(hub.sessions[sid], admin=role == "admin")

            state.lives[sid] = LiveSwarm(sid, session.session.name,
                                         session_world(session.session.data), session.swarm,
                                         activities=[activity], commander=commanders[sid],
                                         task_text=session.task.text, links=links)

    sync()
    state.refresh = sync
    app.mount(SERVE_MOUNT, create_console_app(state, base=SERVE_MOUNT))
    staff = next((k.key for k in keys if k.role.value == "operator"), None)

    def ready(url: str) -> None:
        suffix = f"?key={staff}" if staff else "?key=OPERATOR_OR_ADMIN_KEY"
        first = next(iter(hub.sessions), "")
        _print(f"web console: {url}{SERVE_MOUNT}/live/{first}{suffix}")

    return ready


def run_replay(args: argparse.Namespace) -> int:
    """Serve the console over recorded runs until interrupted; bad paths exit 2."""
    from benchmark.server.serve import serve_asgi
    from console.app import ConsoleState, create_console_app
    from console.auth import ConsoleAuth
    from console.results_index import open_paths
    try:
        index = open_paths(args.paths, args.session)
    except ValueError as error:
        print(f"mavswarm: {error}", file=sys.stderr)
        return 2
    if args.key:
        auth, _ = ConsoleAuth.single_key(args.key)
    else:
        auth = ConsoleAuth(lambda _key: None, open_access=True)
    state = ConsoleState(auth, index=index, session_folders=_folders(args.session_dirs))
    app = create_console_app(state)
    suffix = f"?key={args.key}" if args.key else ""

    def ready(url: str) -> None:
        if index.runs:
            _print(f"run inspector: {url}/runs{suffix}")
        if index.truth is not None:
            _print(f"replay of {index.truth.path.name}: {url}/replay{suffix}")

    try:
        asyncio.run(serve_asgi(app, host=args.host, port=args.port, on_ready=ready))
    except KeyboardInterrupt:
        return 130
    except OSError as error:
        print(f"mavswarm: {error}", file=sys.stderr)
        return 2
    return 0
