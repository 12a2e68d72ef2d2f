"""The gateway over a lossy link: chains of take_off, move_to 200 m, take_photo, land.

    ./dev perf lossy_link [--drones 3] [--chains 5] [--loss 0,0.05,0.2] [--latency-ms 0]
                           [--jitter-ms 0] [--via relay|faults] [--clock lockstep|stepped]
                           [--primitives basic|all] [--seed 1]

Each drone flies --chains chains side by side with the others (one thread of control per
drone, as the benchmark's agents do). A chain succeeds when all its primitives answer `ok`:
take_off, move_to 200 m, take_photo, land; with `--primitives all` also a 5 s hover and a
two-waypoint path (missions), and every other chain returns home instead of landing.
Every outcome is compared with the ground truth right after it, and these are counted as
false reports: `rejected` or `timeout` while the truth shows the drone did act (it took off,
arrived, took the photo, started the mission, returned, landed). `unknown` is never false:
it says the outcome could not be known.

--via relay: a UDP relay between the swarm and the gateway drops (and delays) whole datagrams
in both directions, seeded, in wall time (how the problem was first measured; it works with
any emulator). --via faults: the emulator's own link faults (emulator.link_faults), decided in
simulated time. Prints, per loss rate: chains ok, false reports, unknown outcomes, wall time.
"""

from __future__ import annotations

import argparse
import asyncio
import math
import random
import socket
import sys
import time
from collections import Counter
from pathlib import Path
from typing import cast

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from emulator.clock import ClockConfig
from emulator.scenario import default_scenario
from emulator.services import SwarmServices
from emulator.swarm import PortPlan, Swarm
from mavlink_gateway import FleetConnection, Gateway, profiles_from_scenario
from mavlink_gateway.pacing import Thinker, run_as, run_concurrently

LOOPBACK = "127.0.0.1"
RATES = {"HEARTBEAT": 1.0, "EXTENDED_SYS_STATE": 1.0, "SYS_STATUS": 1.0,
         "BATTERY_STATUS": 1.0, "HOME_POSITION": 0.5, "GLOBAL_POSITION_INT": 2.0,
         "LOCAL_POSITION_NED": 0.5, "ATTITUDE": 0.5, "GPS_RAW_INT": 0.5, "VFR_HUD": 0.5}


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind((LOOPBACK, 0))
        return int(s.getsockname()[1])


class Relay(asyncio.DatagramProtocol):
    """Swarm <-> gateway datagrams through one socket; each dropped with probability `loss`
    and delayed by latency +- jitter (wall time), from a seeded generator."""

    def __init__(self, gateway_port: int, loss: float, latency_s: float, jitter_s: float,
                 seed: int) -> None:
        self.gateway = (LOOPBACK, gateway_port)
        self.swarm: tuple[str, int] | None = None
        self.loss, self.latency_s, self.jitter_s = loss, latency_s, jitter_s
        self.rng = random.Random(seed)
        self.transport: asyncio.DatagramTransport | None = None
        self.dropped = self.passed = 0

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = cast(asyncio.DatagramTransport, transport)

    def datagram_received(self, data: bytes, addr: tuple[str, int]) -> None:
        if addr[1] != self.gateway[1]:
            self.swarm = addr
            to = self.gateway
        elif self.swarm is not None:
            to = self.swarm
        else:
            return
        if self.rng.random() < self.loss:
            self.dropped += 1
            return
        self.passed += 1
        delay = max(0.0, self.latency_s + self.jitter_s * (2.0 * self.rng.random() - 1.0))
        assert self.transport is not None
        if delay > 0.0:
            asyncio.get_running_loop().call_later(delay, self.transport.sendto, data, to)
        else:
            self.transport.sendto(data, to)


async def chain(gw: Gateway, swarm: Swarm, drone: str, k: int, tally: Counter[str],
                every: bool) -> None:
    ap = swarm.fleet.autopilots[swarm.fleet.index_by_id[drone]]

    def judge(name: str, status: str, acted: bool) -> None:
        tally[f"{name}:{status}"] += 1
        if status == "unknown":
            tally["unknown"] += 1
        elif acted and status in ("rejected", "timeout"):
            tally["false"] += 1

    x, y, _ = ap.position_m
    ok = True
    out = await gw.take_off(drone, 10.0)
    judge("take_off", out.status.value, ap.in_air)
    ok &= out.ok
    if ap.in_air:
        dx = 200.0 if k % 2 == 0 else -200.0
        out = await gw.move_to(drone, x + dx, y, 10.0)
        judge("move_to", out.status.value, math.dist(ap.position_m[:2], (x + dx, y)) < 2.0)
        ok &= out.ok
        photos = ap.photo_count
        out = await gw.take_photo(drone)
        judge("take_photo", out.status.value, ap.photo_count > photos)
        ok &= out.ok
        if every:
            x1, y1, _ = ap.position_m
            path = [[x1, y1 + 20.0], [x1 - dx / 10.0, y1 + 20.0]]
            for name, args in (("hover", (5.0,)), ("move_along_path", (path,))):
                t0 = swarm.fleet.now_s
                out = await getattr(gw, name)(drone, *args)
                started = swarm.recorder.events(drone, t0_s=t0, kinds=("mission_start",))
                judge(name, out.status.value, bool(started))
                ok &= out.ok
        if every and k % 2:
            out = await gw.return_home(drone)
            judge("return_home", out.status.value, not ap.in_air
                  and math.dist(ap.position_m[:2], ap.home_m[:2]) < 1.0)
        else:
            out = await gw.land(drone)
            judge("land", out.status.value, not ap.in_air)
        ok &= out.ok
    tally["chains_ok" if ok else "chains_failed"] += 1


async def drone_thread(gw: Gateway, swarm: Swarm, drone: str, chains: int,
                       tally: Counter[str], every: bool) -> None:
    for k in range(chains):
        await chain(gw, swarm, drone, k, tally, every)
        ap = swarm.fleet.autopilots[swarm.fleet.index_by_id[drone]]
        if ap.in_air:  # a failed chain left it flying: put it down for the next one
            await gw.land(drone)


async def run(loss: float, args: argparse.Namespace) -> dict[str, float]:
    scenario = default_scenario(args.drones)
    api_port = free_port()
    relay: Relay | None = None
    faults = None
    if args.via == "relay":
        relay_port = free_port()
        relay = Relay(api_port, loss, args.latency_ms / 1000.0, args.jitter_ms / 1000.0,
                      args.seed)
        loop = asyncio.get_running_loop()
        await loop.create_datagram_endpoint(lambda: relay, local_addr=(LOOPBACK, relay_port))
        swarm_dest = relay_port
    else:
        from emulator.link_faults import LinkFaults, LinkProfile
        profile = LinkProfile(loss=loss, latency_ms=args.latency_ms, jitter_ms=args.jitter_ms)
        faults = LinkFaults(seed=args.seed, uplink=profile, downlink=profile)
        swarm_dest = api_port
    lockstep = args.clock == "lockstep"
    clock = ClockConfig(stepped=True, lockstep=lockstep)
    ports = PortPlan(bind_host=LOOPBACK, api_port=swarm_dest, gcs_port=0)
    swarm_kwargs = {"link_faults": faults} if faults is not None else {}
    tally: Counter[str] = Counter()
    async with Swarm(scenario, clock=clock, ports=ports, telemetry_hz=RATES,
                     **swarm_kwargs) as swarm:
        services = SwarmServices(swarm)
        async with await FleetConnection.connect(
                f"udpin://{LOOPBACK}:{api_port}", profiles_from_scenario(scenario),
                scenario.world.origin, landed_state_hz=None if lockstep else 10.0,
                timeout_s=60.0) as fleet:
            gw = Gateway(fleet.drones, services)
            t0 = time.perf_counter()
            thinker = Thinker(services)
            await run_as(thinker, run_concurrently(services, [
                drone_thread(gw, swarm, d, args.chains, tally, args.primitives == "all")
                for d in fleet.drones]))
            thinker.close()
            wall = time.perf_counter() - t0
    result = {"loss": loss, "wall_s": wall, **{k: float(v) for k, v in tally.items()}}
    if relay is not None:
        result["datagrams_dropped"] = relay.dropped
    return result


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--drones", type=int, default=3)
    p.add_argument("--chains", type=int, default=5)
    p.add_argument("--loss", default="0,0.05,0.2", help="comma-separated loss rates")
    p.add_argument("--latency-ms", type=float, default=0.0)
    p.add_argument("--jitter-ms", type=float, default=0.0)
    p.add_argument("--via", choices=("relay", "faults"), default="faults")
    p.add_argument("--clock", choices=("lockstep", "stepped"), default="lockstep")
    p.add_argument("--primitives", choices=("basic", "all"), default="basic",
                   help="all: also hover, a path and return home")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("-v", "--verbose", action="store_true", help="print every outcome count")
    args = p.parse_args()
    total = args.drones * args.chains
    steps = "take_off, move_to 200 m, take_photo, " + (
        "hover, path, land or return_home" if args.primitives == "all" else "land")
    print(f"{args.drones} drones x {args.chains} chains ({steps}), via {args.via}, "
          f"{args.clock} clock, latency {args.latency_ms:g} +- "
          f"{args.jitter_ms:g} ms, seed {args.seed}")
    print(f"{'loss':>6} {'chains ok':>10} {'false reports':>14} {'unknown':>8} {'wall s':>8}")
    for loss in (float(v) for v in args.loss.split(",")):
        r = asyncio.run(run(loss, args))
        print(f"{loss:>6.0%} {int(r.get('chains_ok', 0)):>4} / {total:<3} "
              f"{int(r.get('false', 0)):>14} {int(r.get('unknown', 0)):>8} "
              f"{r['wall_s']:>8.1f}", flush=True)
        if args.verbose:
            print("       " + ", ".join(f"{k}={int(v)}" for k, v in sorted(r.items())
                                        if ":" in k))


if __name__ == "__main__":
    main()
