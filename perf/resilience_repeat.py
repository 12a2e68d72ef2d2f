"""Shipped resilience sessions flown twice by the oracle: whether the same seed gives the same
truth and verdicts with the tasks' faults striking.

    ./dev perf resilience_repeat [--sessions ID ...] [--tasks N] [--runs 2]

Runs each session's first N tasks (default all 20) with the oracle on a lockstep clock, --runs
times, each run in a fresh swarm. For each task it keeps the record (wall-clock fields and the
replay dropped) and a SHA-256 of the ground truth of the task's window (every trajectory sample
and every event, byte for byte). Prints the pass count and wall time of each run, how many
tasks carried faults and how many struck, and whether the runs' truth digests and records are
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
from benchmark.authoring.suite import SESSIONS_DIR
from benchmark.running.episode import EpisodeOptions, run_task, swarm_gateway
from swarm_agents.oracle import OracleAgent

DROPPED = ("wall_time_s", "overhead_s", "replay")
DEFAULT_SESSIONS = ("resilience-easy-1", "resilience-moderate-3")


def truth_digest(recorder: Any, t0_s: float, t1_s: float) -> str:
    digest = hashlib.sha256()
    for vehicle in recorder.vehicle_ids:
        digest.update(np.ascontiguousarray(recorder.trajectory(vehicle, t0_s, t1_s)).tobytes())
    for event in recorder.events(t0_s=t0_s, t1_s=t1_s):
        digest.update(json.dumps([event.t_s, event.vehicle_id, event.kind, event.data],
                                 sort_keys=True, default=dict).encode())
    return digest.hexdigest()


async def run_once(paths: list[Path], tasks: int
                   ) -> tuple[list[tuple[dict[str, Any], str, int]], float]:
    """(record, truth digest, faults that struck) per task, and the wall time."""
    results = []
    wall0 = time.perf_counter()
    for path in paths:
        session = load_session(path)
        agent = OracleAgent(session.scenario, {t.id: t.oracle for t in session.tasks})
        async with swarm_gateway(session, lockstep=True) as (swarm, services, gateway):
            for task in session.tasks[:tasks]:
                record = await run_task(session, task, agent, swarm, services, gateway,
                                        EpisodeOptions())
                t0_s, t1_s = record["window_s"]
                struck = sum(1 for e in swarm.recorder.events(t0_s=t0_s, t1_s=t1_s)
                             if e.kind == "failure" and e.data.get("source") == "schedule")
                stable = {k: v for k, v in record.items() if k not in DROPPED}
                results.append((stable, truth_digest(swarm.recorder, t0_s, t1_s), struck))
    return results, time.perf_counter() - wall0


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--sessions", nargs="+", default=list(DEFAULT_SESSIONS))
    p.add_argument("--tasks", type=int, default=20)
    p.add_argument("--runs", type=int, default=2)
    args = p.parse_args()
    paths = [SESSIONS_DIR / f"{name}.json" for name in args.sessions]
    missing = [str(path) for path in paths if not path.exists()]
    if missing:
        p.error(f"no such session file: {', '.join(missing)}")
    if args.runs < 2 or args.tasks < 1:
        p.error("need --runs >= 2 (runs are compared) and --tasks >= 1")
    faulty = sum(1 for path in paths for t in load_session(path).tasks[:args.tasks]
                 if t.faults is not None)
    print(f"oracle, sessions {', '.join(args.sessions)}, first {args.tasks} tasks each, "
          f"lockstep; {faulty} tasks carry hidden faults")
    runs = []
    for k in range(args.runs):
        results, wall = asyncio.run(run_once(paths, args.tasks))
        passed = sum(r["passed"] for r, _, _ in results)
        struck = sum(n for _, _, n in results)
        print(f"run {k + 1}: {passed}/{len(results)} passed, {struck} scheduled failures "
              f"struck, {wall:.1f} s wall", flush=True)
        runs.append(results)
    for k, results in enumerate(runs[1:], start=2):
        same_truth = [a[1] == b[1] for a, b in zip(runs[0], results, strict=True)]
        same_records = [a[0] == b[0] for a, b in zip(runs[0], results, strict=True)]
        print(f"run {k} vs 1: truth identical in {sum(same_truth)}/{len(same_truth)} tasks, "
              f"records (checks, verdicts, end states) identical in "
              f"{sum(same_records)}/{len(same_records)}")


if __name__ == "__main__":
    main()
