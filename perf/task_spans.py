"""Where a benchmark task's wall time goes: the oracle (lockstep, as `bench run`) over a few
sessions in this process, each phase of each task timed.

    ./dev perf task_spans                                   # one session per level
    ./dev perf task_spans --sessions area_search-extreme-1 --tasks 5

Phases: start (swarm up, MAVSDK connected and every drone's telemetry ready), reset (the
operator's reset until telemetry shows it), agent (the oracle's tool calls over MAVLink, with
the flight they wait on), play-out (goals still under way at the end, then settling),
evaluate (the hidden checks), replay (the window's replay data and the end state), and close.
Prints per session the seconds of each phase, the process's CPU seconds and the share of wall
time the event loop spent waiting (idle). Writing records happens in the driver, not here.

The process's CPU is then split by thread (Linux /proc/self/task), start-up included: the
event loop (this script's main thread: the swarm, the gateway, the oracle's tool calls and
the evaluation), the oracle's planning threads, MAVSDK's own threads (its receiving, parsing
and timers, and the Python callbacks it runs there to hand each subscribed message to the
event loop) and the rest (other Python threads, and threads that ended before the session
did).
"""

from __future__ import annotations

import argparse
import asyncio
import os
import sys
import threading
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import machine_line, table, thread_cpu_s

from benchmark.authoring.session_file import load_session
from benchmark.authoring.suite import SESSIONS_DIR
from benchmark.running import episode
from swarm_agents.oracle import OracleAgent
from swarm_agents.oracle.agent import PLANNING_THREAD

DEFAULT = ("area_search-easy-1", "target_assignment-moderate-1", "resilience-hard-1",
           "area_assignment_and_patrol-intermediate-1", "target_tracking-extreme-1",
           "area_search-extreme-1")
PHASES = ("start", "reset", "agent", "play_out", "evaluate", "replay", "close")
ROLES = ("loop", "planning", "MAVSDK", "other")
SPANS: defaultdict[str, float] = defaultdict(float)


def _timed(name: str, fn: Any) -> Any:
    if asyncio.iscoroutinefunction(fn):
        async def run_async(*args: Any, **kwargs: Any) -> Any:
            t0 = time.perf_counter()
            try:
                return await fn(*args, **kwargs)
            finally:
                SPANS[name] += time.perf_counter() - t0
        return run_async

    def run(*args: Any, **kwargs: Any) -> Any:
        t0 = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            SPANS[name] += time.perf_counter() - t0
    return run


def _instrument() -> None:
    episode.reset_for_task = _timed("reset", episode.reset_for_task)
    episode._run_agent = _timed("agent", episode._run_agent)
    episode._play_out = _timed("play_out", episode._play_out)
    episode.evaluate = _timed("evaluate", episode.evaluate)
    episode.encode_window = _timed("replay", episode.encode_window)


class _IdleMeter:
    """Wall seconds the event loop spent in select() (waiting on sockets and timers)."""

    def __init__(self) -> None:
        self.idle_s = 0.0

    def install(self, loop: asyncio.AbstractEventLoop) -> None:
        selector = loop._selector  # type: ignore[attr-defined]
        select = selector.select

        def timed(timeout: float | None = None) -> Any:
            t0 = time.perf_counter()
            try:
                return select(timeout)
            finally:
                self.idle_s += time.perf_counter() - t0
        selector.select = timed


async def _fly(path: Path, limit: int | None, idle: _IdleMeter) -> list[object]:
    idle.install(asyncio.get_running_loop())
    session = load_session(path)
    plans = {t.id: t.oracle for t in session.tasks if t.oracle is not None}
    agent = OracleAgent(session.scenario, plans)
    SPANS.clear()
    wall0, cpu0, threads0 = time.perf_counter(), time.process_time(), thread_cpu_s()
    context = episode.session_swarm(session, episode.EpisodeOptions())
    swarm, services, gateway = await context.__aenter__()
    SPANS["start"] = time.perf_counter() - wall0
    tasks = session.tasks[:limit]
    for task in tasks:
        await episode.run_task(session, task, agent, swarm, services, gateway,
                               episode.EpisodeOptions())
    threads = _cpu_by_role({tid: cpu_s - threads0.get(tid, 0.0)
                            for tid, cpu_s in thread_cpu_s().items()})
    t_close = time.perf_counter()
    await context.__aexit__(None, None, None)
    SPANS["close"] = time.perf_counter() - t_close
    wall = time.perf_counter() - wall0
    n = len(tasks)
    cpu = time.process_time() - cpu0
    threads["other"] = cpu - sum(threads.values())
    return [path.stem, n, f"{wall:.1f}", f"{wall / n:.3f}",
            *(f"{SPANS[p]:.2f}" for p in PHASES),
            f"{cpu:.1f}", f"{100 * idle.idle_s / wall:.0f} %",
            *(f"{100 * threads[r] / cpu:.0f} %" for r in ROLES)]


def _cpu_by_role(by_thread: dict[int, float]) -> dict[str, float]:
    """CPU seconds of the live threads by role (see the module's docstring)."""
    names = {t.native_id: t.name for t in threading.enumerate()}
    main = threading.main_thread().native_id
    roles = dict.fromkeys(ROLES[:-1], 0.0)
    for tid, cpu_s in by_thread.items():
        name = names.get(tid)
        if tid == main:
            roles["loop"] += cpu_s
        elif name is None:
            roles["MAVSDK"] += cpu_s  # threads Python did not start
        elif name.startswith(PLANNING_THREAD):
            roles["planning"] += cpu_s
    return roles


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sessions", nargs="*", default=list(DEFAULT), metavar="ID")
    p.add_argument("--tasks", type=int, help="the first N tasks of each session")
    args = p.parse_args()
    import logging
    logging.disable(logging.WARNING)
    _instrument()
    print(machine_line(), flush=True)
    rows = []
    for ident in args.sessions:
        rows.append(asyncio.run(_fly(SESSIONS_DIR / f"{ident}.json", args.tasks, _IdleMeter())))
        print("  ", rows[-1], flush=True)
    print("\n" + table(["session", "tasks", "wall s", "s/task", *PHASES, "CPU s", "idle",
                        *(f"CPU {r}" for r in ROLES)], rows))
    print(f"load average after: {Path('/proc/loadavg').read_text().strip()}")


if __name__ == "__main__":
    main()
