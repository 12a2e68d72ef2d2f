"""Scaling of `--backend ray`: one suite run on a Ray cluster at several worker counts, wall
time per count (and, with --local, the same counts on the local backend beside it).

Without --ray-address it starts a cluster of `ray start` nodes on this machine's loopback
range (tests/ray_cluster.py: a head that runs no session, and --nodes worker nodes sharing
the largest worker count's CPUs between them) and stops it at the end.

    ./dev perf ray_scaling                                   # smoke suite, 1 2 3 workers
    ./dev perf ray_scaling --suite full --workers 2 4 8 --nodes 2 --local
    ./dev perf ray_scaling --sessions a.json b.json --ray-address 10.0.0.5:6379
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import machine_line, table

from benchmark.authoring.suite import SUITES, suite_paths
from benchmark.running.orchestrator import RunPlan, run_benchmark
from benchmark.running.results import read_records


@contextlib.contextmanager
def _cluster(address: str, nodes: int, max_workers: int) -> Iterator[str]:
    """The cluster's address: the given one, or a local cluster's for the duration."""
    if address:
        yield address
        return
    from tests.ray_cluster import LocalRayCluster
    started = time.perf_counter()
    with LocalRayCluster(head_cpus=0) as cluster:
        for _ in range(nodes):
            cluster.add_node(num_cpus=math.ceil(max_workers / nodes))
        os.environ.update(cluster.env)  # this process is the driver
        print(f"local Ray cluster at {cluster.address}: head and {nodes} node(s) of "
              f"{math.ceil(max_workers / nodes)} CPU(s), up in "
              f"{time.perf_counter() - started:.1f} s", flush=True)
        yield cluster.address


def _run(paths: Sequence[Path], limit: int | None, agent: str, workers: int, backend: str,
         address: str) -> list[object]:
    with tempfile.TemporaryDirectory() as tmp:
        plan = RunPlan(sessions=tuple(paths), agent=agent, workers=workers, out_dir=Path(tmp),
                       task_limit=limit, backend=backend,
                       ray_address=address if backend == "ray" else "")
        started = time.perf_counter()
        outcome = run_benchmark(plan, progress=lambda line: None)
        wall_s = time.perf_counter() - started
        records = read_records(plan.results_path)
    passed = sum(r["passed"] for r in records)
    return [backend, workers, len(records), passed, len(outcome.errors), f"{wall_s:.1f}",
            f"{wall_s / max(len(records), 1):.2f}"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--suite", choices=SUITES, default="smoke")
    group.add_argument("--sessions", type=Path, nargs="+", metavar="FILE")
    parser.add_argument("--agent", default="oracle")
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2, 3],
                        help="worker counts to run at")
    parser.add_argument("--nodes", type=int, default=2, help="worker nodes of a local cluster")
    parser.add_argument("--ray-address", default="", help="run on this cluster instead")
    parser.add_argument("--local", action="store_true",
                        help="also run each count on the local backend")
    args = parser.parse_args()
    if args.sessions:
        paths, limit, label = tuple(args.sessions), None, "custom sessions"
    else:
        (paths, limit), label = suite_paths(args.suite), f"{args.suite} suite"
    print(machine_line())
    print(f"{args.agent} agent on the {label}: {len(paths)} sessions"
          f"{f', {limit} tasks each' if limit else ''}")
    rows = []
    with _cluster(args.ray_address, args.nodes, max(args.workers)) as address:
        for workers in args.workers:
            rows.append(_run(paths, limit, args.agent, workers, "ray", address))
            print(table(HEADERS, rows[-1:]).splitlines()[-1], flush=True)
            if args.local:
                rows.append(_run(paths, limit, args.agent, workers, "local", ""))
                print(table(HEADERS, rows[-1:]).splitlines()[-1], flush=True)
    print()
    print(table(HEADERS, rows))


HEADERS = ("backend", "workers", "tasks", "passed", "errors", "wall s", "s/task")

if __name__ == "__main__":
    main()
