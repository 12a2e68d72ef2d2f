"""The oracle over the smoke suite through faulty links: pass rate, wall-time cost, and whether
the same seed gives the same truth.

    ./dev perf lossy_smoke [--loss 0.2] [--latency-ms 50] [--jitter-ms 20] [--seed 1]
                            [--runs 2] [--sessions ID ...]

Runs the smoke sessions' first 6 tasks with the oracle on a lockstep clock, once on a clean
link and --runs times with the link faults in both directions of every link (seeded). For each
task it keeps the record (wall-clock fields dropped) and a SHA-256 of the ground truth of the
task's window (every trajectory sample and every event, byte for byte). Prints the pass rate
and wall time of each run, and whether the faulty runs' truth digests and records are
identical.
"""

from __future__ import annotations

import argparse
import asyncio
import hashlib
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmark.authoring.session_file import load_session
from benchmark.authoring.suite import SMOKE_TASKS, suite_paths
from benchmark.running.episode import EpisodeOptions, run_task, swarm_gateway
from emulator.link_faults import LinkFaults, LinkProfile
from swarm_agents.oracle import OracleAgent

WALL_FIELDS = ("wall_time_s", "overhead_s")


def truth_digest(swarm: Any, t0_s: float, t1_s: float) -> str:
    recorder = swarm.recorder
    digest = hashlib.sha256()
    for vehicle in recorder.vehicle_ids:
        digest.update(np.ascontiguousarray(recorder.trajectory(vehicle, t0_s, t1_s)).tobytes())
    for event in recorder.events(t0_s=t0_s, t1_s=t1_s):
        digest.update(json.dumps([event.t_s, event.vehicle_id, event.kind, event.data],
                                 sort_keys=True, default=str).encode())
    return digest.hexdigest()


async def run_suite(paths: list[Path], faults: LinkFaults | None
                    ) -> tuple[list[tuple[dict[str, Any], str]], float]:
    results = []
    wall0 = time.perf_counter()
    for path in paths:
        session = load_session(path)
        plans = {t.id: t.oracle for t in session.tasks if t.oracle is not None}
        agent = OracleAgent(session.scenario, plans)
        async with swarm_gateway(session, lockstep=True, link_faults=faults) as (
                swarm, services, gateway):
            for task in session.tasks[:SMOKE_TASKS]:
                t0_s = services.clock_s()
                record = await run_task(session, task, agent, swarm, services, gateway,
                                        EpisodeOptions())
                stable = {k: v for k, v in record.items() if k not in WALL_FIELDS}
                results.append((stable, truth_digest(swarm, t0_s, services.clock_s())))
    return results, time.perf_counter() - wall0


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--loss", type=float, default=0.2)
    p.add_argument("--latency-ms", type=float, default=50.0)
    p.add_argument("--jitter-ms", type=float, default=20.0)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--runs", type=int, default=2, help="faulty runs (compared with each other)")
    p.add_argument("--sessions", nargs="+", help="session ids (default: the smoke suite)")
    args = p.parse_args()
    paths, _limit = suite_paths("smoke")
    if args.sessions:
        paths = tuple(path for path in paths if path.stem in args.sessions)
    profile = LinkProfile(loss=args.loss, latency_ms=args.latency_ms, jitter_ms=args.jitter_ms)
    faults = LinkFaults(seed=args.seed, uplink=profile, downlink=profile)
    print(f"oracle, {len(paths)} smoke sessions x {SMOKE_TASKS} tasks, lockstep; faults: loss "
          f"{args.loss:.0%}, latency {args.latency_ms:g} +- {args.jitter_ms:g} ms both ways, "
          f"seed {args.seed}")
    clean, clean_wall = asyncio.run(run_suite(list(paths), None))
    passed = sum(r["passed"] for r, _ in clean)
    print(f"clean link:  {passed}/{len(clean)} passed, {clean_wall:.1f} s wall", flush=True)
    runs = []
    for k in range(args.runs):
        results, wall = asyncio.run(run_suite(list(paths), faults))
        passed = sum(r["passed"] for r, _ in results)
        print(f"faulty run {k + 1}: {passed}/{len(results)} passed, {wall:.1f} s wall "
              f"({wall / clean_wall:.2f}x the clean link)", flush=True)
        runs.append(results)
    for k, results in enumerate(runs[1:], start=2):
        same_truth = [a[1] == b[1] for a, b in zip(runs[0], results, strict=True)]
        same_records = [a[0] == b[0] for a, b in zip(runs[0], results, strict=True)]
        print(f"faulty run {k} vs 1: truth identical in {sum(same_truth)}/{len(same_truth)} "
              f"tasks, records identical in {sum(same_records)}/{len(same_records)}")
    verdicts = [r["passed"] for r, _ in clean] == [r["passed"] for r, _ in runs[0]]
    print(f"verdicts equal to the clean link's: {verdicts}")


if __name__ == "__main__":
    main()
