"""`mavswarm up`: a swarm of emulated PX4 quadrotors until Ctrl-C."""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import multiprocessing
import multiprocessing.connection
import os
import signal
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path

from emulator.capacity import (
    MAX_VEHICLES_PER_NETWORK,
    Machine,
    check_capacity,
    process_networks,
)
from emulator.clock import ClockConfig
from emulator.link_faults import (
    LinkFaults,
    add_link_arguments,
    link_faults_from_args,
)
from emulator.reference_mapping import notes_to_show
from emulator.scenario import Scenario, ScenarioError, default_scenario, load_scenario
from emulator.swarm import PortPlan, Swarm

__all__ = ["MAX_VEHICLES_PER_NETWORK", "Attachment", "add_parsers", "run_up"]

SUPERVISE_POLL_S = 0.5  # how often the process of several networks looks for Ctrl-C
STOP_GRACE_S = 60.0  # how long a network process may take to stop before it is killed


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """The `up` command, on the `mavswarm` command's subparsers."""
    up = sub.add_parser("up", help="run a swarm of emulated PX4 quadrotors until Ctrl-C")
    up.set_defaults(run=run_up)
    up.add_argument("--drones", type=int, help="number of vehicles (default 5, or the session's)")
    up.add_argument("--session", type=Path, help="MultiUAV-Plat or mavswarm session JSON file")
    up.add_argument("--speed", type=float, default=1.0, help="simulation speed x real time")
    up.add_argument("--stepped", action="store_true",
                    help="advance simulated time only while a vehicle executes a goal")
    up.add_argument("--physics-hz", type=float, default=50.0, help="physics step rate")
    up.add_argument("--bind-host", default="0.0.0.0")
    up.add_argument("--bind-port", type=int, default=None,
                    help="swarm socket port (default 14580; per-vehicle: base, default 18570)")
    up.add_argument("--api-port", type=int, default=14540, help="MAVSDK port (0: none)")
    up.add_argument("--gcs-port", type=int, default=14550, help="QGroundControl port (0: none)")
    up.add_argument("--per-vehicle-ports", action="store_true",
                    help="one socket and port pair per vehicle (PX4 multi-instance style)")
    up.add_argument("--shared-local-origin", action="store_true",
                    help="LOCAL_POSITION_NED about the session origin for every vehicle "
                         "(default: each vehicle's own start point, as PX4 instances)")
    up.add_argument("--truth-out", type=Path,
                    help="ground-truth record written on exit (default: runs/<time>.truth.npz)")
    up.add_argument("--no-truth", action="store_true", help="do not write the ground truth")
    up.add_argument("--verbose", action="store_true", help="also print info logging")
    add_link_arguments(up)


def run_up(args: argparse.Namespace) -> int:
    """Run the `up` command; errors in the arguments or the session are printed, exit 2.
    `args.attachments` (optional, `Attachment`s) run beside each swarm."""
    try:
        return _up(args)
    except (ScenarioError, ValueError, OSError) as error:
        print(f"mavswarm: {error}", file=sys.stderr)
        return 2


def _link_faults(args: argparse.Namespace, scenario: Scenario | None) -> LinkFaults | None:
    """The session file's ``link_faults`` (if any), with the --link options on top."""
    base = None
    if args.session is not None and scenario is not None:
        try:
            raw = json.loads(Path(args.session).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            raw = None  # load_scenario read it already: not reached in practice
        if isinstance(raw, dict) and "link_faults" in raw:
            base = LinkFaults.from_json(raw["link_faults"], f"{args.session}: link_faults",
                                        [v.id for v in scenario.vehicles])
    faults = link_faults_from_args(args, base)
    if faults is not None and faults.clean:
        return None
    return faults


def _scenario(args: argparse.Namespace) -> Scenario:
    if args.session is None:
        return default_scenario(args.drones if args.drones is not None else 5)
    scenario = load_scenario(args.session)
    for note in notes_to_show(scenario.notes):
        print(f"mavswarm: note: {note}", file=sys.stderr)
    if args.drones is not None:
        if not 1 <= args.drones <= len(scenario.vehicles):
            raise ScenarioError(
                f"{args.session}: --drones {args.drones} but the session has "
                f"{len(scenario.vehicles)} drones"
            )
        scenario = replace(scenario, vehicles=scenario.vehicles[: args.drones])
    return scenario


Attachment = Callable[[Swarm, "int | None"], contextlib.AbstractAsyncContextManager[object]]
"""Something a composing command runs beside a swarm of `up` while it flies (the MQTT bus, the
web console): called with the swarm and its network index (None for a single network)."""


async def _serve(scenario: Scenario, clock: ClockConfig, ports: PortPlan, label: str,
                 truth_out: Path | None, attachments: Sequence[Attachment] = (),
                 network: int | None = None, link_faults: LinkFaults | None = None,
                 shared_local_origin: bool = False) -> None:
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        with contextlib.suppress(NotImplementedError):
            loop.add_signal_handler(sig, stop.set)
    async with Swarm(scenario, clock=clock, ports=ports, link_faults=link_faults,
                     shared_local_origin=shared_local_origin) as swarm:
        mode = "stepped" if clock.stepped else f"{clock.speed:g}x real time"
        print(f"{label}{swarm.n} vehicles from {scenario.source}, {mode}, "
              f"physics {clock.physics_hz:g} Hz", flush=True)
        if link_faults is not None:
            print(f"{label}{swarm.faults.gate.describe()}", flush=True)
        for url in swarm.connection_urls():
            print(f"{label}  {url}", flush=True)
        async with contextlib.AsyncExitStack() as stack:
            for attach in attachments:
                await stack.enter_async_context(attach(swarm, network))
            await stop.wait()
        stats = swarm.stats()
        print(f"{label}stopping after {stats.sim_time_s:.1f} s simulated in "
              f"{stats.wall_time_s:.1f} s (real-time factor {stats.real_time_factor:.2f}); "
              f"{stats.frames_bad} malformed frames dropped", flush=True)
        if truth_out is not None:
            path = swarm.export_truth(truth_out)
            print(f"{label}ground truth written to {path}", flush=True)


def _run_network(scenario: Scenario, clock: ClockConfig, ports: PortPlan, label: str,
                 truth_out: Path | None, attachments: Sequence[Attachment], network: int,
                 link_faults: LinkFaults | None, shared_local_origin: bool) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides when to stop
    with contextlib.suppress(KeyboardInterrupt):
        asyncio.run(_serve(scenario, clock, ports, label, truth_out, attachments, network,
                           link_faults, shared_local_origin))


def _truth_path(args: argparse.Namespace) -> Path | None:
    if args.no_truth:
        return None
    if args.truth_out is not None:
        return args.truth_out
    stamp = time.strftime("%Y%m%d-%H%M%S", time.gmtime())
    return Path("runs") / f"mavswarm-{stamp}.truth.npz"


def _writable(path: Path) -> Path:
    """`path` if a file can be written there at the end (its folder made now); else OSError."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise OSError(f"--truth-out {path}: cannot make its folder: {error.strerror}") from None
    if path.is_dir() or not os.access(path.parent, os.W_OK):
        raise OSError(f"--truth-out {path}: not a file that can be written")
    return path


def _up(args: argparse.Namespace) -> int:
    args.truth_out = _truth_path(args)
    if args.truth_out is not None:
        _writable(args.truth_out)
    if args.drones is not None and args.drones < 1:
        raise ValueError(f"--drones must be at least 1, got {args.drones}")
    clock = ClockConfig(physics_hz=args.physics_hz, speed=args.speed, stepped=args.stepped)
    total = args.drones
    if args.session is None and total is not None and total > MAX_VEHICLES_PER_NETWORK:
        if args.per_vehicle_ports:
            raise ValueError(f"--per-vehicle-ports is limited to {MAX_VEHICLES_PER_NETWORK} "
                             "vehicles (one MAVLink network)")
        check_capacity(total, Machine.measure())  # before any process starts
        return _up_networks(args, clock, total)
    scenario = _scenario(args)
    check_capacity(len(scenario.vehicles), Machine.measure())
    link_faults = _link_faults(args, scenario)
    bind = args.bind_port if args.bind_port is not None else (
        18570 if args.per_vehicle_ports else 14580)
    ports = PortPlan(bind_host=args.bind_host, bind_port=bind, api_port=args.api_port,
                     gcs_port=args.gcs_port, per_vehicle=args.per_vehicle_ports)
    with contextlib.suppress(KeyboardInterrupt):
        asyncio.run(_serve(scenario, clock, ports, "", args.truth_out,
                           tuple(getattr(args, "attachments", ())), None, link_faults,
                           getattr(args, "shared_local_origin", False)))
    return 0


def _up_networks(args: argparse.Namespace, clock: ClockConfig, total: int) -> int:
    """More than 250 vehicles: MAVLink networks of at most 250, network j at ports bind + j,
    api + j and gcs + j, in as few processes as hold them (emulator.capacity)."""
    bind = args.bind_port if args.bind_port is not None else 14580
    layout = PortPlan(bind_host=args.bind_host, bind_port=bind, api_port=args.api_port,
                      gcs_port=args.gcs_port)
    layout.check(total)  # every network's ports, before any process starts
    link_faults = _link_faults(args, None)
    plan = process_networks(total)
    procs = []
    for nets in plan:
        j = nets.start
        n = min(total, nets.stop * MAX_VEHICLES_PER_NETWORK) - j * MAX_VEHICLES_PER_NETWORK
        ports = PortPlan(bind_host=args.bind_host, bind_port=bind + j if bind else 0,
                         api_port=args.api_port + j if args.api_port else 0,
                         gcs_port=args.gcs_port + j if args.gcs_port else 0)
        name = f"net{j}" if len(nets) == 1 else f"nets{j}-{nets.stop - 1}"
        truth = args.truth_out.with_suffix(f".{name}.npz") if args.truth_out else None
        label = f"[net {j}] " if len(nets) == 1 else f"[nets {j}-{nets.stop - 1}] "
        proc = multiprocessing.Process(
            target=_run_network, args=(default_scenario(n), clock, ports, label, truth,
                                       tuple(getattr(args, "attachments", ())),
                                       None if len(plan) == 1 else j, link_faults,
                                       getattr(args, "shared_local_origin", False)),
            name=f"mavswarm-{name}",
        )
        proc.start()
        procs.append(proc)
    _supervise(procs)
    return 0


def _supervise(procs: list[multiprocessing.Process]) -> None:
    """Wait for the network processes; on Ctrl-C or SIGTERM stop them all (each writes its
    figures and truth), killing any still running after STOP_GRACE_S.

    The wait wakes every SUPERVISE_POLL_S: a signal the kernel hands to another thread of this
    process (numpy's, say) does not interrupt a blocking wait of the main thread, so a plain
    `join` could sleep through Ctrl-C; and SIGTERM is handled as Ctrl-C, so stopping this
    process never leaves its networks running on their own."""
    previous = {sig: signal.signal(sig, signal.default_int_handler)  # KeyboardInterrupt
                for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        while any(proc.is_alive() for proc in procs):
            multiprocessing.connection.wait([proc.sentinel for proc in procs],
                                            timeout=SUPERVISE_POLL_S)
    except KeyboardInterrupt:
        for proc in procs:
            proc.terminate()
        deadline = time.monotonic() + STOP_GRACE_S
        for proc in procs:
            proc.join(max(0.0, deadline - time.monotonic()))
        for proc in procs:
            if proc.is_alive():
                print(f"{proc.name} did not stop within {STOP_GRACE_S:g} s: killed", flush=True)
                proc.kill()
                proc.join()
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)

