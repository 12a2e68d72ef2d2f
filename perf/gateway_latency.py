"""Gateway overhead per primitive, and nearby() latency in a crowded world.

    ./dev perf gateway_latency [--drones 5] [--calls 100] [--flight-calls 20]
                                [--targets 100] [--obstacles 100] [--extent 1000]
                                [--radii 50,100,200] [--nearby-calls 200] [--seed 1]
                                [--physics-hz 50] [--telemetry-hz NAME=HZ,...]
                                [--profile FILE] [-v]

Everything runs in this one process and one asyncio loop, as an agent harness would run it:
`Swarm(..., ClockConfig(stepped=True))` on 127.0.0.1, `SwarmServices`, a `FleetConnection`
(MAVSDK, GROUND_STATION, udpin on 127.0.0.1) and a `Gateway`. Times are wall times of the
awaited call (time.perf_counter), p50/p95 by nearest rank.

Part 1 (default_scenario(--drones), drone d1 unless stated):
  - command round trips while d1 hovers at 10 m: raw MAVSDK calls (set_takeoff_altitude, a
    PARAM_SET round trip; arm/disarm of d2 on the ground, COMMAND_LONG -> ACK; takeoff refused
    by the autopilot because d1 is airborne; set_home; camera.take_photo, IMAGE_START_CAPTURE
    -> ACK) and gateway primitives decided by one command round trip (move_to above d1's
    GF_MAX_VER_DIST = 50 m, which the gateway lets through - the profile ceiling is 120 m -
    and the autopilot refuses; set_home; take_photo; rotate to the heading d1 already has);
  - flight: --flight-calls cycles of take_off(10 m), move_to (20 m leg), rotate(+90 deg),
    hover(1 s), land. "sim s" is the simulated time the call covered; "physics ms" the wall
    time the stepped clock spent in Fleet.run during the call (stepped mode runs simulated
    flight flat out), "beyond ms" = wall - physics: what the call cost beyond simulating the
    flight (MAVLink round trips, telemetry latency, gateway waits);
  - rejected primitives (precondition checks, nothing sent): take_off while airborne,
    land on the ground, move_to of an unknown drone, move_to with a NaN coordinate.
Part 2: a world of --targets targets (discs and polygons) and --obstacles obstacles (discs,
  ellipses, polygons) spread uniformly over an --extent m square, 4 drones per perceived
  radius in --radii, on the ground; gw.nearby(d) and the raw services.sense(d), round robin.
--telemetry-hz sets the part 1 emulator's stream rates (Swarm(telemetry_hz=...)), to see how
much of a flight primitive's time is waiting for the next telemetry sample. The gateway asks
each drone for EXTENDED_SYS_STATE at mavlink_gateway.drone_link.LANDED_STATE_HZ itself.
"""

from __future__ import annotations

import argparse
import asyncio
import cProfile
import math
import os
import pstats
import random
import sys
import time
from collections import Counter
from collections.abc import Awaitable, Callable

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import LOOPBACK, free_udp_port, machine_line, pct, table
from _mavsdk import quiet_mavsdk, warnings_line

from emulator.clock import ClockConfig
from emulator.geo import DEFAULT_ORIGIN
from emulator.scenario import DEFAULT_MODEL, Scenario, VehicleSpec, default_scenario
from emulator.services import SwarmServices
from emulator.swarm import PortPlan, Swarm
from emulator.world import CALM, Obstacle, Target, World
from mavlink_gateway import FleetConnection, Gateway, Outcome, profiles_from_scenario
from mavlink_gateway import core as gateway_core
from mavlink_gateway.payload import perception_dict
from mavlink_vocabulary import MavComponent

CMD_TARGET_MS = 5.0
NEARBY_TARGET_MS = 2.0
VERBOSE = False
CEILING_M = 50.0  # d1's GF_MAX_VER_DIST in part 1: a move_to above it is refused by PX4 rules


def ms(v: float) -> str:
    return f"{v * 1000:.2f}"


class Meter:
    """Wall time spent simulating: wraps Fleet.run (what the stepped clock calls)."""

    def __init__(self, swarm: Swarm) -> None:
        self.physics_s = 0.0
        fleet = swarm.fleet
        run = fleet.run

        def timed_run(*args, **kwargs):
            t = time.perf_counter()
            try:
                return run(*args, **kwargs)
            finally:
                self.physics_s += time.perf_counter() - t

        fleet.run = timed_run  # type: ignore[method-assign]


class Sample:
    def __init__(self) -> None:
        self.wall: list[float] = []
        self.sim: list[float] = []
        self.physics: list[float] = []
        self.status: Counter[str] = Counter()


async def timed(samples: dict[str, Sample], name: str, services: SwarmServices, meter: Meter,
                call: Callable[[], Awaitable[object]], expect: str | None = None) -> object:
    s = samples.setdefault(name, Sample())
    sim0, phys0 = services.clock_s(), meter.physics_s
    t0 = time.perf_counter()
    try:
        out = await call()
        status = out.status.value if isinstance(out, Outcome) else "ok"
    except Exception as error:  # raw MAVSDK refusals raise
        out, status = error, f"raised {type(error).__name__}"
    wall = time.perf_counter() - t0
    s.wall.append(wall)
    s.sim.append(services.clock_s() - sim0)
    s.physics.append(meter.physics_s - phys0)
    s.status[status] += 1
    if VERBOSE:
        print(f"  {name}: {wall * 1000:.2f} ms, {status}", file=sys.stderr, flush=True)
    if expect is not None and not status.startswith(expect):
        detail = out.message if isinstance(out, Outcome) else repr(out)
        raise RuntimeError(f"{name}: expected {expect}, got {status}: {detail}")
    return out


def rows_of(samples: dict[str, Sample], names: list[str]) -> list[list[object]]:
    rows = []
    for name in names:
        s = samples[name]
        beyond = [w - p for w, p in zip(s.wall, s.physics, strict=True)]
        status = ", ".join(f"{k} {v}" for k, v in sorted(s.status.items()))
        rows.append([name, len(s.wall), ms(pct(s.wall, 50)), ms(pct(s.wall, 95)),
                     f"{pct(s.sim, 50):.2f}", ms(pct(s.physics, 50)), ms(pct(beyond, 50)),
                     ms(pct(beyond, 95)), status])
    return rows


HEADERS = ["primitive", "calls", "wall p50 ms", "wall p95 ms", "sim p50 s", "physics p50 ms",
           "beyond p50 ms", "beyond p95 ms", "status"]


async def until(pred: Callable[[], bool], timeout_s: float = 10.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not pred():
        if time.monotonic() > deadline:
            raise TimeoutError("telemetry did not settle")
        await asyncio.sleep(0.01)


# ------------------------------------------------------------------------------ part 1
async def part1(args: argparse.Namespace) -> tuple[dict[str, Sample], list[str]]:
    sc = default_scenario(args.drones)
    port = free_udp_port()
    clock = ClockConfig(stepped=True, physics_hz=args.physics_hz)
    ports = PortPlan(bind_host=LOOPBACK, api_host=LOOPBACK, api_port=port, gcs_port=0)
    samples: dict[str, Sample] = {}
    async with Swarm(sc, clock=clock, ports=ports, telemetry_hz=args.telemetry_hz) as swarm:
        services = SwarmServices(swarm)
        meter = Meter(swarm)
        async with await FleetConnection.connect(f"udpin://{LOOPBACK}:{port}",
                                                 profiles_from_scenario(sc),
                                                 sc.world.origin) as fleet:
            gw = Gateway(fleet.drones, services)
            d1, d2 = fleet.drones["d1"], fleet.drones["d2"]

            async def run(name, call, expect=None):
                return await timed(samples, name, services, meter, call, expect)

            await d1.param.set_param_float("GF_MAX_VER_DIST", CEILING_M)
            await run("take_off", lambda: gw.take_off("d1", 10.0), "ok")
            await asyncio.sleep(0.2)

            # ---- command round trips (d1 hovering, d2 on the ground)
            for i in range(args.calls):
                await run("raw set_takeoff_altitude",
                          lambda i=i: d1.action.set_takeoff_altitude(10.0 + i % 2))
                await run("raw arm (d2)", d2.action.arm)
                await run("raw disarm (d2)", d2.action.disarm)
                await run("raw takeoff, refused", d1.action.takeoff, "raised")
                await run("raw set_home", lambda: d1.action.set_home(True, 0.0, 0.0, 0.0))
                await run("raw camera.take_photo",
                          lambda: d1.camera.take_photo(MavComponent.CAMERA))
            heading = round(d1.heading_deg)
            for _ in range(args.calls):
                await run("move_to, refused by autopilot",
                          lambda: gw.move_to("d1", 0.0, 0.0, CEILING_M + 30.0), "rejected")
                await run("set_home", lambda: gw.set_home("d1"), "ok")
                await run("take_photo", lambda: gw.take_photo("d1"), "ok")
                await run("rotate, to current heading", lambda: gw.rotate("d1", heading), "ok")
            command_rows = ["raw set_takeoff_altitude", "raw arm (d2)", "raw disarm (d2)",
                            "raw takeoff, refused", "raw set_home", "raw camera.take_photo",
                            "move_to, refused by autopilot",
                            "set_home", "take_photo", "rotate, to current heading"]

            # ---- rejected (precondition) primitives
            for _ in range(args.calls):
                await run("take_off while airborne", lambda: gw.take_off("d1", 10.0),
                          "rejected")
                await run("land on the ground (d2)", lambda: gw.land("d2"), "rejected")
                await run("move_to unknown drone", lambda: gw.move_to("x9", 1, 2, 3),
                          "rejected")
                await run("move_to NaN", lambda: gw.move_to("d1", math.nan, 0, 10),
                          "rejected")
            rejected_rows = ["take_off while airborne", "land on the ground (d2)",
                             "move_to unknown drone", "move_to NaN"]

            # ---- flight cycles
            await run("land", lambda: gw.land("d1"), "ok")
            samples.pop("take_off")  # the first take-off (above) was not part of a cycle
            samples.pop("land")
            await until(lambda: not d1.armed)
            for i in range(args.flight_calls):
                await run("take_off", lambda: gw.take_off("d1", 10.0), "ok")
                x = 20.0 if i % 2 == 0 else 0.0
                await run("move_to", lambda x=x: gw.move_to("d1", x, 0.0, 10.0), "ok")
                h = (d1.heading_deg + 90.0) % 360.0
                await run("rotate", lambda h=h: gw.rotate("d1", h), "ok")
                await run("hover", lambda: gw.hover("d1", 1.0), "ok")
                await run("land", lambda: gw.land("d1"), "ok")
                await until(lambda: not d1.armed)  # auto-disarm after touch-down
            flight_rows = ["take_off", "move_to", "rotate", "hover", "land"]
    return samples, [command_rows, flight_rows, rejected_rows]


# ------------------------------------------------------------------------------ part 2
def crowded_scenario(args: argparse.Namespace) -> Scenario:
    rng = random.Random(args.seed)
    half = args.extent / 2.0
    radii = [float(r) for r in args.radii.split(",")]
    spots = [(-half / 2, -half / 2), (half / 2, -half / 2), (-half / 2, half / 2), (0.0, 0.0)]
    vehicles = []
    for j, radius in enumerate(radii):
        for sx, sy in spots:
            k = len(vehicles)
            pos = (sx + 5.0 * j, sy, 0.0)
            vehicles.append(VehicleSpec(
                id=f"d{k + 1}", name=f"Drone {k + 1}", model=DEFAULT_MODEL, position_m=pos,
                heading_deg=0.0, home_m=pos, max_speed_m_s=12.0, max_altitude_m=120.0,
                perceived_radius_m=radius, task_radius_m=20.0, battery_pct=100.0,
                battery_capacity_mah=5000.0))
    clear = [(sx + 5.0 * j, sy) for j in range(len(radii)) for sx, sy in spots]

    def free_point(margin: float) -> tuple[float, float]:
        while True:
            x, y = rng.uniform(-half, half), rng.uniform(-half, half)
            if all(math.hypot(x - a, y - b) > margin + 10.0 for a, b in clear):
                return x, y

    obstacles = []
    for i in range(args.obstacles):
        kind = i % 3
        c = free_point(40.0)
        if kind == 0:
            obstacles.append(Obstacle.disc(f"o{i + 1}", f"Disc {i + 1}", c,
                                           rng.uniform(3.0, 25.0), height_m=rng.choice([0, 30])))
        elif kind == 1:
            obstacles.append(Obstacle.ellipse(f"o{i + 1}", f"Ellipse {i + 1}", c,
                                              rng.uniform(5.0, 30.0), rng.uniform(5.0, 30.0)))
        else:
            n = rng.randint(3, 8)
            r = rng.uniform(8.0, 30.0)
            verts = [(c[0] + r * math.cos(2 * math.pi * v / n),
                      c[1] + r * math.sin(2 * math.pi * v / n)) for v in range(n)]
            obstacles.append(Obstacle.polygon(f"o{i + 1}", f"Polygon {i + 1}", verts))
    targets = []
    for i in range(args.targets):
        c = free_point(0.0)
        kind = i % 4
        if kind == 0:
            targets.append(Target.polygon(f"t{i + 1}", f"Area {i + 1}",
                                          [(c[0], c[1]), (c[0] + 40, c[1]), (c[0] + 40, c[1] + 25),
                                           (c[0], c[1] + 25)]))
        elif kind == 1:
            targets.append(Target.disc(f"t{i + 1}", f"Search {i + 1}", "circle", (*c, 0.0),
                                       rng.uniform(10.0, 40.0)))
        elif kind == 2:
            targets.append(Target.disc(f"t{i + 1}", f"Station {i + 1}", "waypoint", (*c, 0.0),
                                       5.0, charge_rate_pct_s=0.5))
        else:
            targets.append(Target.disc(f"t{i + 1}", f"Fixed {i + 1}", "fixed", (*c, 0.0), 2.0))
    world = World(obstacles=obstacles, targets=targets, wind=CALM, origin=DEFAULT_ORIGIN)
    return Scenario("gateway_latency crowded world", "others", world, tuple(vehicles), "bench")


async def part2(args: argparse.Namespace) -> list[list[object]]:
    sc = crowded_scenario(args)
    port = free_udp_port()
    ports = PortPlan(bind_host=LOOPBACK, api_host=LOOPBACK, api_port=port, gcs_port=0)
    rows = []
    async with Swarm(sc, clock=ClockConfig(stepped=True), ports=ports) as swarm:
        services = SwarmServices(swarm)
        async with await FleetConnection.connect(f"udpin://{LOOPBACK}:{port}",
                                                 profiles_from_scenario(sc),
                                                 sc.world.origin) as fleet:
            gw = Gateway(fleet.drones, services)
            by_radius: dict[float, list[str]] = {}
            for spec in sc.vehicles:
                by_radius.setdefault(spec.perceived_radius_m, []).append(spec.id)
            for radius, ids in by_radius.items():
                gw_t, sense_t, dict_t, counts = [], [], [], Counter()
                for i in range(args.nearby_calls):
                    d = ids[i % len(ids)]
                    t0 = time.perf_counter()
                    out = gw.nearby(d)
                    t1 = time.perf_counter()
                    p = services.sense(d)
                    t2 = time.perf_counter()
                    perception_dict(p)
                    t3 = time.perf_counter()
                    gw_t.append(t1 - t0)
                    sense_t.append(t2 - t1)
                    dict_t.append(t3 - t2)
                    assert out.ok and out.data is not None, out.message
                    for key in ("targets", "obstacles", "drones"):
                        counts[key] += len(out.data[key])
                    await asyncio.sleep(0)  # let telemetry in between calls
                n = args.nearby_calls
                rows.append([f"{radius:g}", n, f"{counts['targets'] / n:.1f}",
                             f"{counts['obstacles'] / n:.1f}", f"{counts['drones'] / n:.1f}",
                             ms(pct(gw_t, 50)), ms(pct(gw_t, 95)), ms(pct(sense_t, 50)),
                             ms(pct(sense_t, 95)), ms(pct(dict_t, 50))])
    return rows


# -------------------------------------------------------------------------------- main
def verdict(value_ms: float, target_ms: float) -> str:
    return f"{'PASS' if value_ms <= target_ms else 'MISS'} ({value_ms:.2f} ms vs <= {target_ms:g})"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--drones", type=int, default=5, help="part 1 swarm size")
    p.add_argument("--calls", type=int, default=100, help="calls per command/rejection row")
    p.add_argument("--flight-calls", type=int, default=20, help="take-off..land cycles")
    p.add_argument("--targets", type=int, default=100)
    p.add_argument("--obstacles", type=int, default=100)
    p.add_argument("--extent", type=float, default=1000.0, help="side of the world square, m")
    p.add_argument("--radii", default="50,100,200", help="perceived radii, m (4 drones each)")
    p.add_argument("--nearby-calls", type=int, default=200, help="calls per radius")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--physics-hz", type=float, default=50.0)
    p.add_argument("--telemetry-hz", default="", metavar="NAME=HZ,...",
                   help="part 1 emulator stream rates, e.g. GLOBAL_POSITION_INT=50 (default: "
                   "the emulator's defaults, 10 Hz position, 1 Hz heartbeat/EXTENDED_SYS_STATE)")
    p.add_argument("--profile", metavar="FILE", help="cProfile part 1 into FILE and print "
                   "the top functions by internal time")
    p.add_argument("-v", "--verbose", action="store_true", help="print every call (stderr)")
    args = p.parse_args()
    global VERBOSE
    VERBOSE = args.verbose
    args.telemetry_hz = {k: float(v) for k, v in
                         (item.split("=") for item in args.telemetry_hz.split(",") if item)}
    quiet_mavsdk()
    print(f"gateway_latency: part 1 default_scenario({args.drones}), stepped clock at "
          f"{args.physics_hz:g} Hz, {args.calls} calls per command row, {args.flight_calls} "
          f"flight cycles; part 2 {args.targets} targets + {args.obstacles} obstacles over "
          f"{args.extent:g} m x {args.extent:g} m, radii {args.radii} m, {args.nearby_calls} "
          f"nearby() calls per radius; swarm, MAVSDK and gateway in one process and loop, "
          f"127.0.0.1; gateway POLL_S {gateway_core.POLL_S * 1000:g} ms; emulator stream "
          f"rates {args.telemetry_hz or 'default'}")
    print(machine_line(), flush=True)

    prof = cProfile.Profile() if args.profile else None
    if prof:
        prof.enable()
    samples, (command_rows, flight_rows, rejected_rows) = asyncio.run(part1(args))
    if prof:
        prof.disable()
        prof.dump_stats(args.profile)
    print("\n1a. command round trips (d1 hovering at 10 m; 'raw' = MAVSDK call, no gateway)")
    print(table(HEADERS, rows_of(samples, command_rows)))
    print("\n1b. flight primitives (stepped mode: simulated flight runs flat out)")
    print(table(HEADERS, rows_of(samples, flight_rows)))
    print("\n1c. rejected primitives (precondition checks, nothing sent)")
    print(table(HEADERS, rows_of(samples, rejected_rows)))

    nearby_rows = asyncio.run(part2(args))
    print(f"\n2. perception: {args.targets} targets, {args.obstacles} obstacles over "
          f"{args.extent:g} m, 4 drones per radius (mean entities sensed per call)")
    print(table(["radius m", "calls", "targets", "obstacles", "drones", "gw.nearby p50 ms",
                 "p95 ms", "services.sense p50 ms", "p95 ms", "perception_dict p50 ms"],
                nearby_rows))

    print("\ntargets:")
    for name in ("move_to, refused by autopilot", "set_home", "take_photo"):
        print(f"  command round trip p50 <= {CMD_TARGET_MS:g} ms, {name}: "
              f"{verdict(pct(samples[name].wall, 50) * 1000, CMD_TARGET_MS)}")
    worst = max(float(r[5]) for r in nearby_rows)
    print(f"  nearby() p50 <= {NEARBY_TARGET_MS:g} ms (worst radius): "
          f"{verdict(worst, NEARBY_TARGET_MS)}")
    print(warnings_line())
    if prof:
        print(f"\ncProfile of part 1 (written to {args.profile}), top 25 by internal time:")
        pstats.Stats(args.profile).sort_stats("tottime").print_stats(25)


if __name__ == "__main__":
    main()
