"""Digests of the oracle's ground truth and records, to show a change left results as they were.

    ./dev perf truth_digest [--suite smoke] [--sessions ID ...] [--tasks N]

Flies the oracle (lockstep clock, as `bench run`) over the sessions of a suite (default: the
smoke suite and its per-session task limit, plus target_tracking-easy-1 for moving targets)
or the named sessions (`--tasks N`: their first N tasks), each session in one swarm, and prints
per session a SHA-256 of its whole ground truth (every trajectory row of every vehicle, every
event, every moving target's rows) and one of its task records without wall-clock fields, with
the CPU seconds the process spent. Run it before and after a change: the digests must match.
"""

from __future__ import annotations

import argparse
import asyncio
import hashlib
import json
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import machine_line, table

from benchmark.authoring.session_file import load_session
from benchmark.authoring.suite import SESSIONS_DIR, suite_paths
from benchmark.running.episode import EpisodeOptions, run_task, swarm_gateway
from swarm_agents.oracle import OracleAgent

WALL_FIELDS = ("wall_time_s", "overhead_s")
TRACKING = "target_tracking-easy-1"


def truth_digest(recorder) -> str:
    digest = hashlib.sha256()
    for vehicle in recorder.vehicle_ids:
        digest.update(recorder.trajectory(vehicle).tobytes())
    for event in recorder.events():
        digest.update(json.dumps([event.t_s, event.vehicle_id, event.kind, event.data],
                                 sort_keys=True, default=str).encode())
    for target in recorder.moving_target_ids:
        digest.update(recorder.target_trajectory(target).tobytes())
    return digest.hexdigest()[:16]


async def fly(path: Path, limit: int | None) -> list[object]:
    session = load_session(path)
    plans = {t.id: t.oracle for t in session.tasks if t.oracle is not None}
    records = hashlib.sha256()
    cpu0 = time.process_time()
    async with swarm_gateway(session, lockstep=True) as (swarm, services, gateway):
        for task in session.tasks[:limit]:
            record = await run_task(session, task, OracleAgent(session.scenario, plans), swarm,
                                    services, gateway, EpisodeOptions())
            stable = {k: v for k, v in record.items() if k not in WALL_FIELDS}
            records.update(json.dumps(stable, sort_keys=True, default=str).encode())
        truth, sim = truth_digest(swarm.recorder), swarm.fleet.now_s
    return [path.stem, len(session.tasks[:limit]), f"{sim:.1f}", truth,
            records.hexdigest()[:16], f"{time.process_time() - cpu0:.2f}"]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--suite", default="smoke")
    p.add_argument("--sessions", nargs="*", metavar="ID", help="session ids instead of a suite")
    p.add_argument("--tasks", type=int, help="with --sessions: the first N tasks of each")
    args = p.parse_args()
    if args.sessions:
        paths, limit = tuple(SESSIONS_DIR / f"{s}.json" for s in args.sessions), args.tasks
    else:
        paths, limit = suite_paths(args.suite)
        paths += (SESSIONS_DIR / f"{TRACKING}.json",)
    print(f"truth_digest: the oracle in lockstep over {len(paths)} session(s)")
    print(machine_line(), flush=True)
    rows = []
    for path in paths:
        rows.append(asyncio.run(fly(path, limit)))
        print("  ", rows[-1], flush=True)
    print("\n" + table(["session", "tasks", "sim s", "truth sha256", "records sha256",
                        "CPU s"], rows))


if __name__ == "__main__":
    main()
