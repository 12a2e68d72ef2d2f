"""CPU time to build one second of full telemetry: one message at a time vs batched.

    ./dev perf telemetry_build [--sizes 10,250,1000] [--seconds 5] [--repeat 3]

No sockets and no event loop: both ways build the bytes of the default streams (39
messages/s per vehicle) for N vehicles over `--seconds` of stream schedule, replaying the
schedule at the cadence each way is driven at in a running swarm.

  one by one  every 5 ms, each due (vehicle, stream) builds a pymavlink message and packs it
              with the vehicle's encoder (VehicleLink.send_stream: the path before batching,
              still used for streams that are not batched)
  batched     every 20 ms, each stream's due vehicles at once (FleetTelemetry + frame_batch)

Above 250 vehicles, one fleet in MAVLink networks of 250, as a swarm runs it. CPU is this
process's CPU time (time.process_time), the best of `--repeat` runs, so the load of a shared
machine distorts it little; the two ways run alternately.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import machine_line, table

from emulator.flight.fleet import Fleet
from emulator.mavlink.frames import frame_batch
from emulator.mavlink.streams import DEFAULT_STREAMS, StreamSchedule
from emulator.mavlink.telemetry import FleetTelemetry
from emulator.mavlink.vehicle_link import VehicleLink
from emulator.scenario import default_scenario


class _Network:
    def __init__(self, n: int) -> None:
        self.fleet = Fleet(default_scenario(n))
        self.schedule = StreamSchedule(n, 0.0)
        self.out: list[bytes] = []
        emit = self.out.append
        self.links = [VehicleLink(ap, lambda _k, data, emit=emit: emit(data), self.schedule,
                                  lambda: 0.0) for ap in self.fleet.autopilots]
        self.telemetry = FleetTelemetry(self.fleet)


def _one_by_one(nets: list[_Network], seconds: float) -> tuple[float, int]:
    frames = 0
    t0 = time.process_time()
    for net in nets:
        schedule = StreamSchedule(net.fleet.n, 0.0)
        links = net.links
        for tick in range(1, int(seconds / 0.005) + 1):
            for msg_id, ks in schedule.due(tick * 0.005):
                for k in ks.tolist():
                    links[k].send_stream(msg_id)
        frames += len(net.out)
        net.out.clear()
    return time.process_time() - t0, frames


def _batched(nets: list[_Network], seconds: float) -> tuple[float, int]:
    frames = 0
    t0 = time.process_time()
    for net in nets:
        schedule = StreamSchedule(net.fleet.n, 0.0)
        tele = net.telemetry
        for tick in range(1, int(seconds / 0.02) + 1):
            parts = [tele.part(msg_id, ks) for msg_id, ks in schedule.due(tick * 0.02)]
            batch = frame_batch(parts)
            data, start = batch.data, 0
            for end in batch.ends.tolist():  # cut into frames, as the swarm hands them on
                net.out.append(data[start:end])
                start = end
        frames += len(net.out)
        net.out.clear()
    return time.process_time() - t0, frames


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", default="10,250,1000")
    p.add_argument("--seconds", type=float, default=5.0)
    p.add_argument("--repeat", type=int, default=3)
    args = p.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    nominal = sum(s.default_hz for s in DEFAULT_STREAMS)
    print(f"telemetry_build: sizes {sizes}, {args.seconds:g} s of default streams "
          f"({nominal:g} messages/s per vehicle), best of {args.repeat}")
    print(machine_line(), flush=True)
    rows = []
    for n in sizes:
        nets = [_Network(n)]
        old, new = [], []
        for _ in range(args.repeat):
            old.append(_one_by_one(nets, args.seconds))
            new.append(_batched(nets, args.seconds))
        (t_old, f_old), (t_new, f_new) = min(old), min(new)
        rows.append([n, f"{f_old / args.seconds:.0f}", f"{100 * t_old / args.seconds:.1f}",
                     f"{1e6 * t_old / f_old:.1f}", f"{f_new / args.seconds:.0f}",
                     f"{100 * t_new / args.seconds:.1f}", f"{1e6 * t_new / f_new:.2f}",
                     f"{t_old / t_new:.1f}x"])
        print("  ", rows[-1], flush=True)
    print("\n" + table(["N", "one by one msgs/s", "CPU %", "us/msg", "batched msgs/s",
                        "CPU %", "us/msg", "speed-up"], rows))
    print("CPU %: CPU seconds per second of telemetry, in % of one core (building and framing "
          "only: no sockets, no physics).")


if __name__ == "__main__":
    main()
