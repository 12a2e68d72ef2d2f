"""What an idle hosted session costs: K sessions' swarms and gateways in one process, as a
hosted run or `bench run` holds them, on the lockstep clock with the clock pinned (every agent
thinking), measured over a window of wall time.

    ./dev perf idle_sessions                                   # 1 and 8 of each level's first
    ./dev perf idle_sessions --sessions area_search-easy-1 --counts 1 8 32 --window-s 10

Prints per session and K: the process's CPU over the window as a share of one core, in all and
per session, split into the event loop's thread (swarm, gateway) and the others (MAVSDK's).
An agent thinking costs nothing; what is left is the swarm's keep-alive telemetry, its loop
and the client's side of the links.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import logging
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import machine_line, table

from benchmark.authoring.session_file import load_session
from benchmark.authoring.suite import SESSIONS_DIR
from benchmark.running.episode import swarm_gateway

LEVELS = ("easy", "intermediate", "moderate", "hard", "extreme")


def _thread_ticks() -> tuple[int, int]:
    """CPU clock ticks of this process's main thread and of all its other threads."""
    main = other = 0
    for tid in os.listdir("/proc/self/task"):
        try:
            stat = Path(f"/proc/self/task/{tid}/stat").read_text()
        except OSError:  # the thread ended meanwhile
            continue
        fields = stat.rsplit(")", 1)[1].split()
        ticks = int(fields[11]) + int(fields[12])
        if tid == str(os.getpid()):
            main += ticks
        else:
            other += ticks
    return main, other


async def _measure(name: str, count: int, settle_s: float, window_s: float) -> list[object]:
    session = load_session(SESSIONS_DIR / f"{name}.json")
    async with contextlib.AsyncExitStack() as stack:
        for _ in range(count):
            swarm, _services, _gateway = await stack.enter_async_context(
                swarm_gateway(session, lockstep=True))
            swarm.pin()  # the agent thinks: the clock stands still
        await asyncio.sleep(settle_s)
        main0, other0 = _thread_ticks()
        cpu0, wall0 = time.process_time(), time.perf_counter()
        await asyncio.sleep(window_s)
        cpu, wall = time.process_time() - cpu0, time.perf_counter() - wall0
        main1, other1 = _thread_ticks()
    hz = os.sysconf("SC_CLK_TCK")
    share = 100.0 * cpu / wall
    return [name, len(session.scenario.vehicles), count, f"{share:.1f}",
            f"{share / count:.2f}", f"{100.0 * (main1 - main0) / hz / wall / count:.2f}",
            f"{100.0 * (other1 - other0) / hz / wall / count:.2f}", f"{os.getloadavg()[0]:.1f}"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sessions", nargs="+", default=[f"area_search-{lv}-1" for lv in LEVELS])
    parser.add_argument("--counts", type=int, nargs="+", default=[1, 8])
    parser.add_argument("--window-s", type=float, default=10.0)
    parser.add_argument("--settle-s", type=float, default=3.0)
    args = parser.parse_args()
    logging.disable(logging.WARNING)
    print(machine_line(), flush=True)
    rows = []
    for name in args.sessions:
        for count in args.counts:
            rows.append(asyncio.run(_measure(name, count, args.settle_s, args.window_s)))
            print("  ", rows[-1], flush=True)
    print(table(["session", "drones", "K", "% of a core", "per session", "loop thread",
                 "other threads", "load avg"], rows))


if __name__ == "__main__":
    main()
