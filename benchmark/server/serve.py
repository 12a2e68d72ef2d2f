"""Serving live sessions to outside agents: the REST API (`serve_rest`) over one or more
sessions, and one session's tools over MCP (`serve_mcp`, stdio or Streamable HTTP).

Each session (a mavswarm or MultiUAV-Plat file) gets a stepped swarm and a gateway; its
current task starts as its first task (free flight for a world without tasks, and an operator
moves it on: `session_control.py`), and the agent acts through an `AgentTools` bound to that
task's budget. Both servers run until their
asyncio task is cancelled (or, under uvicorn, until SIGINT/SIGTERM).

API keys are given as `role[:session[/drone]]=key` (role agent, operator or admin; only an agent
key names a session, and may leave it out when one session is served; naming a drone makes it
that drone's agent, one thread of its own). With no keys given, one agent key per session (per
drone with `--keys-per-drone`) plus an operator and an admin key are generated and printed.

The clock is lockstep by default (`--clock stepped` for the stepped one): simulated time runs
only while every thread of a session's agent waits on the world (`agent_threads.py`).
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import functools
import sys
from collections.abc import AsyncIterator, Callable, Sequence
from pathlib import Path
from typing import Any, Literal, TextIO

import uvicorn

from benchmark.authoring.importer import load_any_session
from benchmark.authoring.session_file import Session
from benchmark.running.episode import CLOCKS
from benchmark.server import Hub, create_app
from benchmark.server.api_keys import ApiKey, generated_keys, parse_api_key
from benchmark.server.api_keys import add_keys as _add_keys
from benchmark.server.http_config import uvicorn_config
from benchmark.server.hub import LiveSession
from benchmark.server.listen import listen_socket
from benchmark.server.operator_rule import served_refusal
from benchmark.server.session_runner import (
    FREE_FLIGHT,
    SessionRunner,
    current_task_tools,
    first_task,
)
from emulator.reference_mapping import notes_to_show
from llm_tools.mcp_server import serve_stdio, streamable_http_app
from llm_tools.registry import served_registry
from mqtt_bus.cli import add_mqtt_arguments, mqtt_options
from mqtt_bus.swarm_bus import gateway_session_bus
from mqtt_bus.topics import check_segment
from mqtt_bus.url import BrokerUrl

__all__ = [
    "FREE_FLIGHT",
    "ApiKey",
    "AppExtension",
    "add_parsers",
    "current_task_tools",
    "generated_keys",
    "live_hub",
    "parse_api_key",
    "run_mcp",
    "run_serve",
    "serve_asgi",
    "serve_mcp",
    "serve_rest",
]

DEFAULT_HOST = "127.0.0.1"
DEFAULT_REST_PORT = 8000
DEFAULT_MCP_PORT = 8765
MCP_PATH = "/mcp"
Transport = Literal["stdio", "http"]
AppExtension = Callable[[Any, Hub, Sequence["ApiKey"]], Callable[[str], None] | None]
TRANSPORTS: tuple[Transport, ...] = ("stdio", "http")


def _load(path: str | Path) -> Session:
    """A session file of either format; the notes on a converted MultiUAV-Plat file are
    printed to stderr."""
    session, notes = load_any_session(path)
    for note in notes_to_show(notes):
        print(f"mavswarm: note: {path}: {note}", file=sys.stderr)
    return session


@contextlib.asynccontextmanager
async def live_hub(session_paths: Sequence[str | Path], physics_hz: float = 50.0, *,
                   clock: str = "lockstep") -> AsyncIterator[Hub]:
    """A Hub with one live session per file (a swarm with `clock`, lockstep or stepped, and
    a gateway each), closed on exit; sessions an operator loads while it runs are closed with
    them. Session ids must be distinct."""
    if not session_paths:
        raise ValueError("session_paths: expected at least one session file, got none")
    sessions = [_load(path) for path in session_paths]
    seen: dict[str, str] = {}
    for session in sessions:
        if session.id in seen:
            raise ValueError(f"session id {session.id!r} is in both {seen[session.id]} and "
                             f"{session.source}")
        seen[session.id] = session.source
        first_task(session)
    hub = Hub()
    hub.session_folders.files.extend(Path(p).resolve() for p in session_paths)
    async with SessionRunner(physics_hz, clock) as runner:
        for session in sessions:
            hub.add_session(await runner.start(session))
        hub.starter = runner.start
        hub.stopper = runner.stop
        yield hub


async def serve_asgi(app: Any, *, host: str, port: int,
                     on_ready: Callable[[str], None] | None = None) -> None:
    """Run `app` under uvicorn until this task is cancelled or the server is told to stop
    by a signal; `on_ready(base_url)` is called once it listens (port 0 picks a free one)."""
    sock = listen_socket(host, port)  # a busy port: one OSError, before uvicorn starts
    server = uvicorn.Server(uvicorn_config(app, host=host, port=port, lifespan="on"))
    task = asyncio.create_task(server.serve(sockets=[sock]))
    try:
        while not server.started:
            if task.done():
                task.result()
                raise RuntimeError(f"uvicorn did not start on {host}:{port}")
            await asyncio.sleep(0.01)
        bound = server.servers[0].sockets[0].getsockname()
        if on_ready is not None:
            on_ready(f"http://{host}:{bound[1]}")
        await asyncio.shield(task)
    except asyncio.CancelledError:
        server.should_exit = True
        with contextlib.suppress(asyncio.CancelledError):
            await task
        raise


def mqtt_refusal(hub: Hub, session_id: str) -> str | None:
    """Why an operator's command over MQTT may not run in a served session now
    (benchmark.server.operator_rule)."""
    return served_refusal(hub, session_id, "commands over MQTT")


async def serve_rest(session_paths: Sequence[str | Path], *, host: str = DEFAULT_HOST,
                     port: int = DEFAULT_REST_PORT, keys: Sequence[str | ApiKey] = (),
                     on_ready: Callable[[str], None] | None = None,
                     out: TextIO | None = None, open_access: bool = False,
                     mqtt: BrokerUrl | None = None, mqtt_osd_hz: float = 2.0,
                     extend: AppExtension | None = None, clock: str = "lockstep",
                     keys_per_drone: bool = False) -> None:
    """Serve the REST API over live sessions from `session_paths` until cancelled. `keys` are
    `role[:session]=key` strings (or ApiKey); with none, keys are generated and printed to
    `out` (stdout by default) with the URL. `open_access` lets requests without a key act as
    the agent of the one session served (MultiUAV-Plat clients send none). `mqtt`: every
    session started here also goes on that broker (docs/mqtt.md). `extend(app, hub,
    keys)` adds routes of a layer above (the web console) and may return what to call with
    the base URL once the server listens. `clock`: lockstep (default) or stepped;
    `keys_per_drone`: generated agent keys are one per drone (per-drone agents)."""
    if open_access and len(session_paths) != 1:
        raise ValueError("--open serves exactly one session: a request without a key must "
                         "know whose agent it is")
    parsed = [k if isinstance(k, ApiKey) else parse_api_key(k) for k in keys]
    out = out or sys.stdout
    async with live_hub(session_paths, clock=clock) as hub, \
            contextlib.AsyncExitStack() as buses:
        if mqtt is not None:
            async def on_bus(live: LiveSession) -> None:
                bus = await buses.enter_async_context(gateway_session_bus(
                    mqtt, live.id, live.swarm, live.gateway, osd_hz=mqtt_osd_hz,
                    refusal=functools.partial(mqtt_refusal, hub, live.id),
                    services=live.services))
                print(f"MQTT: {mqtt.redacted()} topics {bus.topics.base}/...", file=out,
                      flush=True)

            for live in list(hub.sessions.values()):
                await on_bus(live)
            start = hub.starter
            if start is not None:  # sessions an operator loads later go on the bus too
                async def start_on_bus(session: Session) -> LiveSession:
                    assert start is not None
                    check_segment(session.id, "session id")  # before its swarm starts
                    live = await start(session)
                    await on_bus(live)
                    return live

                hub.starter = start_on_bus
        if not parsed:
            drones = {sid: list(live.gateway.drones) for sid, live in hub.sessions.items()}
            parsed = generated_keys(list(hub.sessions), drones if keys_per_drone else None)
            print("generated API keys (send one in the X-API-Key header):", file=out)
            for key in parsed:
                print(f"  {key.spec()}", file=out)
        hub.open_access = open_access
        _add_keys(hub, parsed)
        app = create_app(hub)
        extended = extend(app, hub, parsed) if extend is not None else None

        def ready(url: str) -> None:
            print(f"mavswarm REST API on {url} (docs at {url}/docs); sessions: "
                  f"{', '.join(hub.sessions)}", file=out, flush=True)
            if extended is not None:
                extended(url)
            if on_ready is not None:
                on_ready(url)

        await serve_asgi(app, host=host, port=port, on_ready=ready)


async def serve_mcp(session_path: str | Path, *, transport: Transport = "stdio",
                    host: str = DEFAULT_HOST, port: int = DEFAULT_MCP_PORT,
                    on_ready: Callable[[str], None] | None = None, clock: str = "lockstep",
                    on_session: Callable[[LiveSession], None] | None = None) -> None:
    """Serve one live session's agent tools over MCP until cancelled (stdio: until the client
    disconnects). Over HTTP the endpoint is `http://host:port/mcp`; nothing is printed to
    stdout (stdio carries the protocol), the URL goes to stderr. The client is the session's
    agent, one thread under a lockstep `clock` (parallel calls go in one `batch` call);
    `on_session(live)` is called once the session runs."""
    if transport not in TRANSPORTS:
        raise ValueError(f"transport: expected one of {TRANSPORTS}, got {transport!r}")
    registry = served_registry()
    async with live_hub([session_path], clock=clock) as hub:
        (live,) = hub.sessions.values()
        if on_session is not None:
            on_session(live)
        if transport == "stdio":
            await serve_stdio(registry, lambda: live.tools)
            return
        app = streamable_http_app(registry, lambda: live.tools, path=MCP_PATH, host=host)

        def ready(url: str) -> None:
            print(f"mavswarm MCP server for session {live.id!r} on {url}{MCP_PATH}",
                  file=sys.stderr, flush=True)
            if on_ready is not None:
                on_ready(f"{url}{MCP_PATH}")

        await serve_asgi(app, host=host, port=port, on_ready=ready)


def _sessions(args: argparse.Namespace) -> list[Path]:
    if args.sessions:
        return list(args.sessions)
    from benchmark.authoring.suite import suite_paths
    paths, _ = suite_paths(args.suite)
    return list(paths)


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """`serve` and `mcp`, on the `mavswarm` command's subparsers."""
    rest = sub.add_parser("serve", help="serve live sessions over the REST API",
                          description="Serve live sessions over the REST API.")
    group = rest.add_mutually_exclusive_group(required=True)
    group.add_argument("--sessions", type=Path, nargs="+", metavar="FILE",
                       help="session files to serve")
    group.add_argument("--suite", choices=("smoke", "full"), help="serve a suite's sessions")
    rest.add_argument("--host", default=DEFAULT_HOST, help="address to listen on")
    rest.add_argument("--port", type=int, default=DEFAULT_REST_PORT, help="TCP port")
    rest.add_argument("--key", dest="keys", action="append", default=[],
                      metavar="ROLE[:SESSION[/DRONE]]=KEY",
                      help="an API key (repeatable); an agent key naming a drone is that "
                           "drone's agent; none: generate and print keys")
    rest.add_argument("--keys-per-drone", action="store_true",
                      help="generated agent keys: one per drone (per-drone agents, each a "
                           "thread of its own) instead of one per session")
    rest.add_argument("--open", dest="open_access", action="store_true",
                      help="requests without a key act as the agent of the one session "
                           "served, as MultiUAV-Plat clients expect (default: 401)")
    rest.add_argument("--verbose", action="store_true",
                      help="also print MAVSDK's own log lines and info logging")
    _add_clock(rest)
    add_mqtt_arguments(rest, session=False)
    rest.set_defaults(run=run_serve)
    mcp = sub.add_parser("mcp", help="serve one session's agent tools over MCP",
                         description="Serve one session's agent tools over MCP.")
    mcp.add_argument("session", type=Path, help="the session file to serve")
    mcp.add_argument("--transport", choices=TRANSPORTS, default="stdio")
    mcp.add_argument("--host", default=DEFAULT_HOST, help="http: address to listen on")
    mcp.add_argument("--port", type=int, default=DEFAULT_MCP_PORT, help="http: TCP port")
    _add_clock(mcp)
    mcp.set_defaults(run=run_mcp)


def _add_clock(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--clock", choices=CLOCKS, default="lockstep",
                        help="lockstep (default): simulated time runs only while the agent's "
                             "requests wait on the world, never while it thinks; stepped: it "
                             "runs whenever a drone executes a goal")


def _guarded(run: Callable[[], None]) -> int:
    from benchmark.authoring.session_file import SessionFileError
    try:
        run()
    except (SessionFileError, ValueError, OSError) as error:
        print(f"mavswarm: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    return 0


def run_serve(args: argparse.Namespace) -> int:
    """Run a parsed `mavswarm serve` until interrupted; bad input is printed, exit 2.
    `args.extend`, when a layer above set it, is passed on to `serve_rest`."""
    return _guarded(lambda: asyncio.run(serve_rest(
        _sessions(args), host=args.host, port=args.port, keys=args.keys,
        open_access=args.open_access, mqtt=mqtt_options(args),
        mqtt_osd_hz=args.mqtt_osd_hz, extend=getattr(args, "extend", None),
        clock=args.clock, keys_per_drone=args.keys_per_drone)))


def run_mcp(args: argparse.Namespace) -> int:
    """Run a parsed `mavswarm mcp` until interrupted or the client leaves."""
    return _guarded(lambda: asyncio.run(serve_mcp(args.session, transport=args.transport,
                                                  host=args.host, port=args.port,
                                                  clock=args.clock)))
