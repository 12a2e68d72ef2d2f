"""Stepped-clock speed-up: a 10-vehicle swarm flies MAVSDK mission_raw missions flat out.

    ./dev perf stepped_speedup [--drones 10] [--physics-hz 50,20,100] [--repeat 1]
                                [--prflt -1|keep] [--timeout 60] [--profile FILE]
                                [--core [--slice 50]] [--sessions [ID ...]] [--tasks N]

The emulator (`Swarm(default_scenario(N), clock=ClockConfig(stepped=True, physics_hz=HZ))`)
runs in its own process on 127.0.0.1; this process is the MAVSDK client (mavsdk.asyncio).
Each vehicle k gets a 5-item mission (NAV_WAYPOINT, frame 6 GLOBAL_RELATIVE_ALT_INT, at
20 + k m): north 250 + Ln m, west Le m, south Ln m, east Le m, back to 20 m north of home,
with Ln = 300 + 10 k, Le = 460 - 10 k: 2,000 m of legs, clear of the scenario's obstacles.
All vehicles: set COM_DISARM_PRFLT (default -1, see --prflt), upload, arm (concurrently),
then start_mission on all concurrently (retried while it times out and the vehicle is not in
MISSION), and wait until MAVSDK reports every mission finished (mission_raw progress +
is_mission_finished). Wall time runs from the first start_mission call to the last
finish seen by MAVSDK; simulated time from just before it (the stepped clock stands still
while nothing flies) to the last vehicle's first mission_complete truth event.

--core flies the same missions on the pure core instead (`Fleet`, no MAVLink, no sockets,
run in slices of 50 steps as a lockstep swarm runs them; `--slice 250` as a stepped swarm
without lockstep does, emulator.swarm.FREE_STEPS_PER_SLICE) and prints the simulated seconds
per CPU second of the physics alone and a SHA-256 of the whole ground truth (every trajectory
row and event), which must not change when the physics code is only made faster (each slice
length has its own: a fast-forward ends with its slice).

--sessions flies the oracle in lockstep over benchmark sessions (default: the five
`*-extreme-1` sessions, 30 drones each; `--tasks N`: their first N tasks), each session in one
swarm with its gateway in this process, as `bench run` does, and prints per session the
simulated seconds, the wall seconds and their ratio (the session's speed-up).
"""

from __future__ import annotations

import argparse
import asyncio
import hashlib
import itertools
import json
import math
import os
import pstats
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import Emulator, free_udp_port, host_busy_s, machine_line, table
from _mavsdk import new_mavsdk, set_executor, wait_for_systems, warnings_line
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.mission_raw import MissionRawAsync
from mavsdk.asyncio.plugins.param import ParamAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync
from mavsdk.plugins.mission_raw import MissionItem, MissionRawError
from mavsdk.plugins.telemetry import FlightMode

from emulator.clock import ClockConfig
from emulator.flight.fleet import Fleet
from emulator.flight.mission import MissionItem as CoreItem
from emulator.scenario import default_scenario
from emulator.swarm import FREE_STEPS_PER_SLICE, STEPS_PER_SLICE

NAV_WAYPOINT = 16
FRAME_GLOBAL_RELATIVE_ALT_INT = 6


def route_m(k: int, home: tuple[float, float]) -> list[tuple[float, float]]:
    """Local ENU waypoints (x east, y north) of vehicle k, from its home (x, y)."""
    x, y = home
    ln, le = 300.0 + 10.0 * k, 460.0 - 10.0 * k
    return [(x, y + 250 + ln), (x - le, y + 250 + ln), (x - le, y + 250), (x, y + 250),
            (x, y + 20)]


def path_length_m(home: tuple[float, float], route: list[tuple[float, float]]) -> float:
    pts = [home, *route]
    return sum(((b[0] - a[0]) ** 2 + (b[1] - a[1]) ** 2) ** 0.5 for a, b in itertools.pairwise(pts))


def mission(k: int, scenario) -> tuple[list[MissionItem], float]:
    spec = scenario.vehicles[k]
    home = spec.home_m[:2]
    origin = scenario.world.origin
    items = []
    route = route_m(k, home)
    for seq, (x, y) in enumerate(route):
        lat, lon, _ = origin.to_geodetic(x, y, 0.0)
        items.append(MissionItem(seq, FRAME_GLOBAL_RELATIVE_ALT_INT, NAV_WAYPOINT,
                                 1 if seq == 0 else 0, 1, 0.0, 0.0, 0.0, float("nan"),
                                 round(lat * 1e7), round(lon * 1e7), 20.0 + k, 0))
    return items, path_length_m(home, route)


async def ready(telemetry: TelemetryAsync) -> None:
    async for health in telemetry.subscribe_health():
        if health.is_armable and health.is_home_position_ok:
            return


async def finished(mission_raw: MissionRawAsync) -> float:
    async for progress in mission_raw.subscribe_mission_progress():
        current, total = progress.current, progress.total
        if total > 0 and (current >= total or (
                current == total - 1 and await mission_raw.is_mission_finished())):
            return time.monotonic()
    raise RuntimeError("mission progress stream ended")


async def start(mission_raw: MissionRawAsync, telemetry: TelemetryAsync) -> int:
    """start_mission, retried while it times out and the vehicle is not in MISSION yet.
    Returns the number of start_mission calls."""
    for attempt in range(1, 6):
        try:
            await mission_raw.start_mission()
            return attempt
        except MissionRawError:
            if await telemetry.flight_mode() == FlightMode.MISSION:
                return attempt
    raise RuntimeError("start_mission failed 5 times")


async def fly(n: int, hz: float, prflt: float | None, timeout_s: float,
              profile_to: str | None = None) -> dict:
    set_executor(n)
    scenario = default_scenario(n)
    port = free_udp_port()
    with Emulator(n, port, clock=ClockConfig(stepped=True, physics_hz=hz),
                  profile_to=profile_to) as emu:
        async with new_mavsdk() as mavsdk:
            t0 = time.monotonic()
            await mavsdk.add_any_connection(f"udpin://127.0.0.1:{port}")
            systems, _, _ = await wait_for_systems(mavsdk, n, t0, timeout_s=30.0)
            assert len(systems) == n, f"found {len(systems)} of {n}"
            actions = [ActionAsync(s) for s in systems]
            missions = [MissionRawAsync(s) for s in systems]
            telemetry = [TelemetryAsync(s) for s in systems]
            await asyncio.gather(*(ready(t) for t in telemetry))
            if prflt is not None:  # see --prflt
                await asyncio.gather(*(ParamAsync(s).set_param_float("COM_DISARM_PRFLT", prflt)
                                       for s in systems))
            plans = [mission(k, scenario) for k in range(n)]
            await asyncio.gather(*(m.upload_mission(p[0])
                                   for m, p in zip(missions, plans, strict=True)))
            await asyncio.gather(*(a.arm() for a in actions))
            done = [asyncio.create_task(finished(m)) for m in missions]
            await asyncio.sleep(0.2)  # let the progress subscriptions settle
            s0 = await asyncio.to_thread(emu.snap)
            if profile_to:
                await asyncio.to_thread(emu.ask, "profile_on")
            w0, h0 = time.monotonic(), host_busy_s()
            calls = await asyncio.gather(
                *(start(m, t) for m, t in zip(missions, telemetry, strict=True)),
                return_exceptions=True)
            await asyncio.wait(done, timeout=timeout_s)
            ends = [t.result() for t in done if t.done() and not t.exception()]
            w1 = max(ends) if len(ends) == n else time.monotonic()
            host = 100 * (host_busy_s() - h0) / (time.monotonic() - w0)
            for t in done:
                t.cancel()
            if profile_to:
                await asyncio.to_thread(emu.ask, "profile_off")
            s1 = await asyncio.to_thread(emu.snap)
            events = await asyncio.to_thread(emu.events)
    first: dict[tuple[int, str], float] = {}
    for k, kind, t in events:
        first.setdefault((k, kind), t)
    starts = [first.get((k, "mission_start"), math.nan) for k in range(n)]
    ends_sim = [first.get((k, "mission_complete"), math.nan) for k in range(n)]
    restarts = sum(kind == "mission_start" for _, kind, _ in events) - n
    if len(ends) < n:
        print(f"  !! only {len(ends)} of {n} missions seen finished within {timeout_s:g} s wall; "
              f"start_mission results {calls}; truth: first starts {starts}, "
              f"first completions {ends_sim}")
    return {"ok": f"{len(ends)}/{n}", "path": sum(p[1] for p in plans) / n,
            "sim": max(ends_sim) - s0["sim"], "wall": w1 - w0,
            "calls": sum(c for c in calls if isinstance(c, int)),
            "failed": sum(not isinstance(c, int) for c in calls),
            "start_spread": max(starts) - min(starts), "restarts": restarts,
            "mission": sum(e - s for s, e in zip(starts, ends_sim, strict=True)) / n,
            "host": host, "cpu": 100 * (s1["cpu"] - s0["cpu"]) / (s1["wall"] - s0["wall"]),
            "cpu_s": s1["cpu"] - s0["cpu"]}


def fly_core(n: int, hz: float, *, digest: bool = True,
             slice_steps: int = STEPS_PER_SLICE) -> dict:
    """The same missions on the pure core, `slice_steps` steps per `Fleet.run`: CPU seconds
    of the physics and a truth digest (`digest=False`: none, "")."""
    scenario = default_scenario(n)
    fleet = Fleet(scenario, physics_hz=hz)
    for k, ap in enumerate(fleet.autopilots):
        ap.set_param("COM_DISARM_PRFLT", -1.0)  # as a stepped swarm sets it
        items = [CoreItem(seq=i.seq, frame=i.frame, command=i.command, x=i.x, y=i.y, z=i.z)
                 for i in mission(k, scenario)[0]]
        ap.mission.replace(items)
        ap.mission.enter_mission_mode()
        ap.arm()
    steps, cpu0 = 0, time.process_time()
    while fleet.any_busy:
        steps += fleet.run(slice_steps)
    cpu = time.process_time() - cpu0
    return {"sim": fleet.now_s, "cpu": cpu, "steps": steps,
            "digest": core_digest(fleet) if digest else ""}


def core_digest(fleet: Fleet) -> str:
    """SHA-256 (16 hex digits) of every trajectory row and truth event of `fleet`, the --core
    digest (its own format: truth_digest.py hashes events and moving targets otherwise)."""
    digest = hashlib.sha256()
    for vehicle in fleet.recorder.vehicle_ids:
        digest.update(fleet.recorder.trajectory(vehicle).tobytes())
    digest.update(json.dumps([e.to_json() for e in fleet.recorder.events()]).encode())
    return digest.hexdigest()[:16]


EXTREME_SESSIONS = ("area_search-extreme-1", "area_assignment_and_patrol-extreme-1",
                    "target_assignment-extreme-1", "target_tracking-extreme-1",
                    "resilience-extreme-1")


async def fly_session(session_id: str, limit: int | None) -> list[object]:
    """The oracle over one session in lockstep: sim s, wall s, speed-up, CPU s."""
    from benchmark.authoring.session_file import load_session
    from benchmark.authoring.suite import SESSIONS_DIR
    from benchmark.running.episode import EpisodeOptions, run_task, swarm_gateway
    from swarm_agents.oracle import OracleAgent

    session = load_session(SESSIONS_DIR / f"{session_id}.json")
    plans = {t.id: t.oracle for t in session.tasks if t.oracle is not None}
    tasks = session.tasks[:limit]
    passed = 0
    async with swarm_gateway(session, lockstep=True) as (swarm, services, gateway):
        sim0, wall0, cpu0 = swarm.fleet.now_s, time.monotonic(), time.process_time()
        for task in tasks:
            record = await run_task(session, task, OracleAgent(session.scenario, plans), swarm,
                                    services, gateway, EpisodeOptions())
            passed += bool(record.get("passed"))
        sim, wall = swarm.fleet.now_s - sim0, time.monotonic() - wall0
        cpu = time.process_time() - cpu0
    return [session_id, len(session.scenario.vehicles), f"{passed}/{len(tasks)}",
            f"{sim:.1f}", f"{wall:.2f}", f"{sim / wall:.0f}", f"{cpu:.2f}", f"{sim / cpu:.0f}",
            f"{os.getloadavg()[0]:.1f}"]


def sessions_main(args) -> None:
    ids = args.sessions or EXTREME_SESSIONS
    print(f"stepped_speedup --sessions: the oracle in lockstep over {len(ids)} session(s)"
          + (f", first {args.tasks} tasks each" if args.tasks else ""))
    print(machine_line(), flush=True)
    rows = []
    for session_id in ids:
        rows.append(asyncio.run(fly_session(session_id, args.tasks)))
        print("  ", rows[-1], flush=True)
    print("\n" + table(["session", "drones", "passed", "sim s", "wall s", "speed-up", "CPU s",
                        "sim s / CPU s", "load avg"], rows))
    print("sim s: simulated time over the session's tasks (operator resets included); wall s: "
          "from the first task's start to the last one's record, oracle and gateway included; "
          "CPU s: this process (emulator, gateway and oracle share it).")


def core_main(args, hzs: list[float]) -> None:
    print(f"stepped_speedup --core: {args.drones} vehicles, the same missions on the pure core "
          f"(no MAVLink) in slices of {args.slice} steps, {args.repeat} run(s) per physics Hz")
    print(machine_line(), flush=True)
    rows = []
    for hz in hzs:
        for _ in range(args.repeat):
            r = fly_core(args.drones, hz, slice_steps=args.slice)
            rows.append([f"{hz:g}", f"{r['sim']:.2f}", r["steps"], f"{r['cpu']:.3f}",
                         f"{r['sim'] / r['cpu']:.0f}", f"{1e6 * r['cpu'] / r['steps']:.1f}",
                         r["digest"], f"{os.getloadavg()[0]:.1f}"])
            print("  ", rows[-1], flush=True)
    print("\n" + table(["physics Hz", "sim s", "steps", "CPU s", "sim s / CPU s", "us / step",
                        "truth sha256", "load avg"], rows))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--drones", type=int, default=10)
    p.add_argument("--physics-hz", default="50,20,100")
    p.add_argument("--repeat", type=int, default=1)
    p.add_argument("--prflt", default="keep",
                   help="COM_DISARM_PRFLT set on every vehicle before arming ('keep': leave "
                        "PX4's 10 s; vehicles whose start_mission is processed after another "
                        "vehicle's flight advanced the shared clock by 10 s get disarmed)")
    p.add_argument("--timeout", type=float, default=60.0, help="wall s to wait per run")
    p.add_argument("--profile", metavar="FILE",
                   help="then fly once more at the first physics Hz under cProfile and print "
                        "the emulator's top functions from the first start_mission to the last "
                        "finish seen")
    p.add_argument("--core", action="store_true",
                   help="fly the missions on the pure core (no MAVLink): physics speed and a "
                        "digest of the ground truth")
    p.add_argument("--slice", type=int, default=STEPS_PER_SLICE,
                   help="with --core: steps per slice (50: a lockstep swarm's; "
                        f"{FREE_STEPS_PER_SLICE}: a stepped swarm's without lockstep)")
    p.add_argument("--sessions", nargs="*", metavar="ID",
                   help="fly the oracle over these benchmark sessions in lockstep (none "
                        "named: the five *-extreme-1 sessions) and print their speed-up")
    p.add_argument("--tasks", type=int, help="with --sessions: the first N tasks of each")
    args = p.parse_args()
    if args.sessions is not None:
        sessions_main(args)
        return
    prflt = None if args.prflt == "keep" else float(args.prflt)
    hzs = [float(h) for h in args.physics_hz.split(",")]
    if args.core:
        core_main(args, hzs)
        return
    print(f"stepped_speedup: {args.drones} vehicles, stepped clock, physics Hz {hzs}, "
          f"{args.repeat} run(s) each; missions of 5 NAV_WAYPOINTs (frame 6, 20-29 m), "
          f"MAVSDK mission_raw, COM_DISARM_PRFLT {args.prflt}, 127.0.0.1")
    print(machine_line(), flush=True)
    rows = []
    for hz in hzs:
        for _ in range(args.repeat):
            r = asyncio.run(fly(args.drones, hz, prflt, args.timeout))
            all_ok = r["ok"] == f"{args.drones}/{args.drones}"
            rows.append([f"{hz:g}", r["ok"], f"{r['path']:.0f}", f"{r['mission']:.1f}",
                         f"{r['start_spread']:.1f}", f"{r['sim']:.1f}", f"{r['wall']:.3f}",
                         f"{r['sim'] / r['wall']:.0f}" if all_ok else "-",
                         f"{r['calls']} ({r['failed']} failed)",
                         r["restarts"] if all_ok else "-", f"{r['cpu']:.0f}",
                         f"{r['sim'] / r['cpu_s']:.0f}" if all_ok else "-", f"{r['host']:.0f}",
                         f"{os.getloadavg()[0]:.1f}"])
            print("  ", rows[-1], flush=True)
    print("\n" + table(["physics Hz", "finished", "path m/veh", "mission sim s/veh",
                        "start spread sim s", "sim s", "wall s", "speed-up", "start_mission calls",
                        "extra mission_start", "emu CPU %", "sim s / emu CPU s", "host busy %",
                        "load avg"], rows))
    print("sim s: simulated time from just before the first start_mission to the last vehicle's "
          "first mission_complete (truth); wall s: first start_mission call to MAVSDK seeing the "
          "last mission finished; speed-up = sim s / wall s (target >= 1,000); sim s / emu CPU s: "
          "simulated seconds per CPU second of the emulator process over the same span (a bound "
          "on the speed-up with a core to itself whatever the load; it leaves out waits on the "
          "client). start spread: "
          "simulated time between the first and the last vehicle's mission_start; extra "
          "mission_start: mission_start truth events beyond one per vehicle (DO_SET_MODE "
          "retransmissions processed late re-start or resume the mission); host busy %: the whole "
          "machine's busy CPU (other users included) during the run, in % of one core.")
    print(warnings_line())
    if args.profile:
        asyncio.run(fly(args.drones, hzs[0], prflt, args.timeout, args.profile))
        st = pstats.Stats(args.profile)
        print(f"\ncProfile of the emulator over one run at {hzs[0]:g} Hz (from the first "
              f"start_mission to the last finish seen), top 25 by own time:")
        st.sort_stats("tottime").print_stats(25)


if __name__ == "__main__":
    main()
