"""Benchmark-suite numbers: size of the shipped suite (tasks, checks, endpoint types) and,
with --run, the wall time of running it with an agent, with the per-task reset and
evaluation overheads.

    ./dev perf bench_suite                       # counts only
    ./dev perf bench_suite --run --workers auto  # full 2500-task oracle run, timed
    ./dev perf bench_suite --run --workers auto --only=-1   # one session per family and level
    ./dev perf bench_suite --run --suite smoke
    ./dev perf bench_suite --family target_tracking --run --agent noop
    ./dev perf bench_suite --family resilience --run --workers 2
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import machine_line, pct

from benchmark.authoring.scenarios import FAMILIES
from benchmark.authoring.session_file import load_session
from benchmark.authoring.suite import suite_paths
from benchmark.running.orchestrator import RunPlan, run_benchmark
from benchmark.running.results import read_records
from benchmark.running.worker_count import AUTO, auto_workers, parse_workers
from benchmark.scoring.validators import endpoints_used, leaf_count


def _counts(paths: tuple[Path, ...], limit: int | None) -> None:
    tasks = checks = 0
    endpoints: Counter[str] = Counter()
    templates: Counter[str] = Counter()
    for path in paths:
        session = load_session(path)
        for task in session.tasks[:limit]:
            assert task.checks is not None, task.error
            tasks += 1
            checks += leaf_count(task.checks)
            endpoints.update(endpoints_used(task.checks))
            templates[task.template] += 1
    print(f"sessions {len(paths)}  tasks {tasks}  checks {checks} "
          f"({checks / max(tasks, 1):.2f} per task)  endpoint types {len(endpoints)}  "
          f"templates {len(templates)}")
    print("endpoints (tasks using each):", ", ".join(f"{k} {v}" for k, v in
                                                     endpoints.most_common()))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--suite", choices=("smoke", "full"), default="full")
    parser.add_argument("--run", action="store_true", help="run the suite and time it")
    parser.add_argument("--agent", default="oracle")
    parser.add_argument("--workers", type=parse_workers, default=2, help="N or auto")
    parser.add_argument("--only", default="", help="only the sessions whose id contains this")
    parser.add_argument("--family", default="", choices=("", *FAMILIES),
                        help="only the sessions of this family")
    args = parser.parse_args()
    paths, limit = suite_paths(args.suite)
    if args.family:
        paths = tuple(p for p in paths if p.stem.startswith(f"{args.family}-"))
        if not paths:
            parser.error(f"no session of family {args.family!r} in suite {args.suite!r}")
    paths = tuple(p for p in paths if args.only in p.stem)
    _counts(paths, limit)
    if not args.run:
        return
    if args.workers == AUTO:
        args.workers = auto_workers(args.agent, len(paths))
    print(machine_line(), flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        plan = RunPlan(sessions=paths, agent=args.agent, workers=args.workers,
                       out_dir=Path(tmp), task_limit=limit)
        started = time.perf_counter()
        outcome = run_benchmark(plan, progress=lambda line: None)
        wall_s = time.perf_counter() - started
        records = read_records(plan.results_path)
    passed = sum(r["passed"] for r in records)
    resets = [r["overhead_s"]["reset"] * 1000 for r in records]
    evals = [r["overhead_s"]["evaluate"] * 1000 for r in records]
    agent = [r["wall_time_s"] for r in records]
    families: Counter[str] = Counter()
    family_passed: Counter[str] = Counter()
    for r in records:
        families[r["family"]] += 1
        family_passed[r["family"]] += bool(r["passed"])
    print("by family:", ", ".join(f"{f} {family_passed[f]}/{n}" for f, n in families.items()))
    finishes = Counter(str(r["finish"]) for r in records)
    print("task ends:", ", ".join(f"{k} {v}" for k, v in finishes.most_common()),
          f"(agent wall max {max(r['wall_time_s'] for r in records):.1f} s)")
    print(f"{args.agent} on {args.suite}: {len(records)} tasks, {passed} passed, "
          f"{len(outcome.errors)} errors, wall {wall_s:.1f} s with {args.workers} workers "
          f"({wall_s / max(len(records), 1):.2f} s per task)")
    print(f"per task: reset p50 {statistics.median(resets):.1f} ms p95 {pct(resets, 95):.1f} ms;"
          f" evaluation p50 {statistics.median(evals):.1f} ms p95 {pct(evals, 95):.1f} ms;"
          f" agent wall p50 {statistics.median(agent):.2f} s p95 {pct(agent, 95):.2f} s;"
          f" simulated {sum(r['sim_time_s'] for r in records) / 3600:.1f} h in all")
    print(f"load average at the end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
