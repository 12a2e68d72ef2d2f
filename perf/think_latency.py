"""Throughput and results under model latency: the oracle thinks THINK_S before every tool call
that acts on the world, as a model would, and many sessions run at once (PROCESSES worker
processes, each holding up to SESSIONS sessions in one event loop; --workers N|auto: N
sessions at once spread as `bench run` spreads an agent that thinks, auto as it picks them).

    ./dev perf think_latency --think-s 2 --workers auto                          # full suite
    ./dev perf think_latency --think-s 2 --workers auto --only extreme           # a subset
    ./dev perf think_latency --think-s 2 --processes 2 --sessions 12
    ./dev perf think_latency --think-s 2 --suite smoke --clock stepped          # the old clock
    ./dev perf think_latency --think-s 2 --workers auto --out DIR   # records, for records_equal

Prints wall time, pass rate, failed tasks, the peak memory of all workers together and the
memory per hosted session (the peak less each worker's own before its first session, over
the sessions hosted at once). With
the lockstep clock, think time costs no simulated time, so every task the oracle passes
without thinking it also passes while thinking; with the stepped clock it does not.
"""

from __future__ import annotations

import argparse
import asyncio
import dataclasses
import json
import multiprocessing
import os
import random
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import machine_line

from agent_contract import AgentTask, AgentTools
from benchmark.authoring.session_file import load_session
from benchmark.authoring.suite import SUITES, suite_paths
from benchmark.running.backends import FOLLOWER_NICE
from benchmark.running.episode import CLOCKS, EpisodeOptions, run_session
from benchmark.running.replay_data import session_world, write_task_replay
from benchmark.running.run_order import run_order, session_heads
from benchmark.running.worker_count import AUTO, auto_workers, hosting_for, parse_workers
from swarm_agents.oracle import OracleAgent

_SPAWN = multiprocessing.get_context("spawn")
PROGRESS_EVERY_S = 60.0


class ThinkingTools:
    """An agent's tools that wait `think_s` (plus up to `jitter_s`) of wall time before every
    tool that acts on the world."""

    def __init__(self, tools: AgentTools, think_s: float, jitter_s: float, rng: random.Random):
        self._tools, self._think_s, self._jitter_s, self._rng = tools, think_s, jitter_s, rng

    def __getattr__(self, name: str) -> Any:
        member = getattr(self._tools, name)
        if name == "concurrently" or not asyncio.iscoroutinefunction(member):
            return member

        async def call(*args: Any, **kwargs: Any) -> Any:
            await asyncio.sleep(self._think_s + self._rng.uniform(0.0, self._jitter_s))
            return await member(*args, **kwargs)
        return call


class ThinkingOracle:
    name = "oracle"

    def __init__(self, oracle: OracleAgent, think_s: float, jitter_s: float, seed: str):
        self._oracle, self._think_s, self._jitter_s = oracle, think_s, jitter_s
        self._rng = random.Random(seed)

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        thinking = ThinkingTools(tools, self._think_s, self._jitter_s, self._rng)
        await self._oracle.run(task, thinking)  # type: ignore[arg-type]


async def _sessions(paths: list[str], args: argparse.Namespace, out: Any) -> None:
    gate = asyncio.Semaphore(args.sessions)

    async def one(path: str) -> None:
        async with gate:
            session = load_session(path)
            if args.task_limit is not None:
                session = dataclasses.replace(session, tasks=session.tasks[:args.task_limit])
            plans = {t.id: t.oracle for t in session.tasks if t.oracle is not None}
            agent = ThinkingOracle(OracleAgent(session.scenario, plans), args.think_s,
                                   args.jitter_s, f"{args.seed}/{path}")
            try:
                await run_session(session, agent, emit=lambda r: out.put(("record", r)),
                                  options=EpisodeOptions(clock=args.clock))
            except Exception as error:  # report, keep the other sessions going
                out.put(("error", f"{path}: {type(error).__name__}: {error}"))

    await asyncio.gather(*(one(p) for p in paths))


def _worker(paths: list[str], args: argparse.Namespace, out: Any, nice: int = 0) -> None:
    os.nice(nice)
    import logging
    logging.disable(logging.WARNING)
    import benchmark.running.orchestrator  # noqa: F401  (what a worker of `bench run` holds)
    from benchmark.running.worker_heap import return_large_blocks
    return_large_blocks()  # as a worker of `bench run` does (benchmark.running.backends)
    out.put(("base", _rss_mb([os.getpid()])))
    asyncio.run(_sessions(paths, args, out))
    out.put(("done", os.getpid()))


def _rss_mb(pids: list[int]) -> float:
    total = 0
    for pid in pids:
        try:
            with open(f"/proc/{pid}/status") as f:
                total += next(int(line.split()[1]) for line in f if line.startswith("VmRSS"))
        except (OSError, StopIteration):
            pass
    return total / 1024.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--suite", choices=SUITES, default="full")
    parser.add_argument("--limit", type=int, default=0, help="first N sessions only")
    parser.add_argument("--only", default="", help="sessions whose id contains this text")
    parser.add_argument("--think-s", type=float, default=2.0)
    parser.add_argument("--jitter-s", type=float, default=0.0)
    parser.add_argument("--clock", choices=CLOCKS, default="lockstep")
    parser.add_argument("--processes", type=int, default=2)
    parser.add_argument("--sessions", type=int, default=8, help="sessions at once per process")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--workers", type=parse_workers, default=None,
                        help="sessions at once in all (or auto), instead of --processes and "
                             "--sessions")
    parser.add_argument("--out", type=Path, default=None,
                        help="write the task records and replays to OUT (as `bench run "
                             "--out` does, to compare with perf/records_equal.py)")
    args = parser.parse_args()
    suite, args.task_limit = suite_paths(args.suite)
    chosen = [p for p in suite if args.only in p.stem][: args.limit or None]
    heads = session_heads(chosen)
    paths = [str(p) for p in run_order(chosen, heads, "thinking")]  # as `bench run` does
    if args.workers is not None:
        at_once = (auto_workers("thinking", len(paths)) if args.workers == AUTO
                   else min(args.workers, len(paths)))
        hosting = hosting_for(at_once)
        args.processes, args.sessions = hosting.processes, hosting.per_process
    print(machine_line())
    print(f"{len(paths)} sessions, think {args.think_s:g} s (+{args.jitter_s:g}) per call, "
          f"clock {args.clock}, {args.processes} processes x {args.sessions} sessions")
    queue = _SPAWN.Queue()
    # as `bench run` spreads them (benchmark.running.backends): with several processes the
    # first hosts the head of the run order at the machine's priority, the others the rest
    # at FOLLOWER_NICE
    if args.processes > 1:
        head, rest = paths[:args.sessions], paths[args.sessions:]
        chunks = [head] + [rest[i::args.processes - 1] for i in range(args.processes - 1)]
    else:
        chunks = [paths]
    workers = [_SPAWN.Process(target=_worker,
                              args=(c, args, queue, FOLLOWER_NICE if k > 0 else 0))
               for k, c in enumerate(chunks) if c]
    start = time.perf_counter()
    for w in workers:
        w.start()
    records: list[dict[str, Any]] = []
    errors: list[str] = []
    finished, peak_mb, base_mb = 0, 0.0, 0.0
    pids = [w.pid for w in workers if w.pid is not None]
    planned = sum(h.tasks if args.task_limit is None else min(h.tasks, args.task_limit)
                  for h in heads.values())
    next_note = start + PROGRESS_EVERY_S
    while finished < len(workers):
        peak_mb = max(peak_mb, _rss_mb(pids))
        if time.perf_counter() >= next_note:
            next_note += PROGRESS_EVERY_S
            print(f"  {time.perf_counter() - start:4.0f} s: {len(records)}/{planned} tasks, "
                  f"{sum(r['passed'] for r in records)} passed, workers {peak_mb:.0f} MB at "
                  f"most, load average {os.getloadavg()[0]:.1f}", flush=True)
        try:
            kind, value = queue.get(timeout=1.0)
        except Exception:
            continue
        if kind == "record":
            records.append(value)
        elif kind == "base":
            base_mb += value
        elif kind == "error":
            errors.append(value)
        else:
            finished += 1
    wall = time.perf_counter() - start
    for w in workers:
        w.join()
    passed = sum(r["passed"] for r in records)
    hosted = min(len(paths), len(workers) * args.sessions)
    print(f"wall {wall:.0f} s; {passed}/{len(records)} tasks passed "
          f"({100.0 * passed / max(1, len(records)):.1f} %); peak RSS of the workers "
          f"{peak_mb:.0f} MB ({base_mb:.0f} MB before their first session; "
          f"{(peak_mb - base_mb) / max(1, hosted):.1f} MB per hosted session, {hosted} at "
          f"once); {len(errors)} session errors; load average now {os.getloadavg()[0]:.1f}")
    if args.out is not None:  # as `bench run --out` lays them out
        args.out.mkdir(parents=True, exist_ok=True)
        worlds = {h.id: session_world(json.loads(p.read_text())) for p, h in heads.items()}
        with (args.out / "results.jsonl").open("w", encoding="utf-8") as f:
            for r in sorted(records, key=lambda r: r["key"]):
                record = {k: v for k, v in r.items() if k != "replay"}
                if r.get("replay") is not None:
                    write_task_replay(args.out, record, r["replay"], worlds[r["session"]])
                f.write(json.dumps(record, sort_keys=True) + "\n")
    for r in records:
        if not r["passed"]:
            failed = [c for c in r["checks"] if not c["passed"]]
            print(f"  FAIL {r['key']}: " + "; ".join(
                f"{c['endpoint']} {c.get('value')}" for c in failed[:3]))
    for e in errors[:10]:
        print("  error", e)


if __name__ == "__main__":
    main()
