"""Millions of hostile MAVLink frames through a swarm's sans-I/O network, in memory.

    ./dev perf protocol_fuzz [--frames 1000000] [--vehicles 3] [--seed 1]
                              [--per-datagram 8] [--turn-every 250]

A swarm of --vehicles is built (not started: no socket), and the seeded frames of
tests/frame_fuzz.py (valid frames of every handled message type with often absurd values,
and frames scrambled, truncated, with bad checksums, wrong lengths, unknown ids, junk) are fed
straight into its `NetworkProtocol.receive_datagram`, --per-datagram frames to a datagram,
with the swarm's answers taken after each datagram and one 20 ms turn of the swarm (physics,
telemetry, link timers) every --turn-every datagrams. Prints the frames, the wall and CPU
time of the storm and the rate, what the decoder made of it, and then asserts that no handler
raised and that every vehicle still answers (a parameter read, an unknown command) and flies
(restored as a ground station would, it takes off and flies a 15 m hop; ground truth).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from emulator.scenario import default_scenario
from tests.frame_fuzz import FrameFuzzer
from tests.memory_fuzz import recover_and_fly, storm
from tests.memory_link import MemoryLink

TARGET_FRAMES = 1_000_000
TARGET_WALL_S = 60.0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=TARGET_FRAMES)
    parser.add_argument("--vehicles", type=int, default=3)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--per-datagram", type=int, default=8)
    parser.add_argument("--turn-every", type=int, default=250)
    args = parser.parse_args()
    if args.frames < 1 or args.vehicles < 1 or args.per_datagram < 1 or args.turn_every < 1:
        parser.error("--frames, --vehicles, --per-datagram and --turn-every must be >= 1")

    t0 = time.perf_counter()
    link = MemoryLink(scenario=default_scenario(args.vehicles))
    params = [dict(ap.params) for ap in link.fleet.autopilots]
    fuzzer = FrameFuzzer(args.seed, systems=tuple(range(1, args.vehicles + 1)))
    setup_s = time.perf_counter() - t0
    cpu0 = time.process_time()
    result = storm(link, fuzzer, args.frames, per_datagram=args.per_datagram,
                   turn_every=args.turn_every)
    cpu_s = time.process_time() - cpu0
    print(f"setup (swarm, {len(fuzzer.corpus)}-frame corpus): {setup_s:.1f} s")
    print(f"storm: {result.line()}")
    print(f"storm CPU time: {cpu_s:.1f} s ({result.frames / cpu_s:,.0f} frames per CPU second)")
    mutations = ", ".join(f"{kind} {count}" for kind, count in sorted(fuzzer.counts.items()))
    print(f"frames sent: {mutations}")
    stats = link.network.stats
    print(f"network: {stats.datagrams_in} datagrams in, {stats.unroutable} frames for unknown "
          f"systems, {stats.handler_errors} handler errors")
    kinds = sorted({e.kind for k in range(args.vehicles)
                    for e in link.swarm.recorder.events(f"d{k + 1}")})
    print(f"what the storm made the vehicles do: {', '.join(kinds)}")
    assert stats.handler_errors == 0 and link.swarm.stats().internal_errors == 0

    t1 = time.perf_counter()
    for system in range(1, args.vehicles + 1):
        recover_and_fly(link, system, params[system - 1])
    assert all(ap.in_air for ap in link.fleet.autopilots)
    print(f"afterwards every vehicle answered and flew a {15:.0f} m hop "
          f"({time.perf_counter() - t1:.1f} s)")
    verdict = "met" if result.frames >= TARGET_FRAMES and result.wall_s < TARGET_WALL_S \
        else "not met"
    print(f"target (>= {TARGET_FRAMES:,} frames in < {TARGET_WALL_S:.0f} s wall): {verdict}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
