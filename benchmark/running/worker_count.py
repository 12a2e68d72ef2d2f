"""How many sessions a benchmark run hosts at once, and in how many processes.

`--workers N` is the number of sessions run at once. An agent that answers at once (the
oracle, noop) gets a worker process per session: its sessions compute most of the time, and
a session never waits on a neighbour's computation. Any other agent mostly thinks, so the
local backend spreads its sessions over one worker process per core, each process hosting
its share side by side in one event loop (a session then costs memory for its swarm and
gateway only, not a process), and over more processes where a core's share would pass
SESSIONS_PER_PROCESS. `--workers auto` picks N from the machine:

- an agent that answers at once (the oracle, noop) keeps a core busy with a few sessions, so
  N = INSTANT_SESSIONS_PER_CORE per core, as far as half the available memory holds a process
  of PROCESS_MB + SESSION_MB for each;
- any other agent (a model, a plug-in, an external one) mostly thinks, so N is what memory
  allows: half the available memory, less one base footprint per process, at SESSION_MB per
  hosted session; and what the cores allow: THINKING_SESSIONS_PER_CORE per core, since a
  session costs CPU even while its agent thinks (its swarm's keep-alive telemetry, its
  client's side of the links) and more while it flies;

never more than the run has units (session x trial), never fewer than 1.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

__all__ = [
    "AUTO",
    "INSTANT_AGENTS",
    "INSTANT_SESSIONS_PER_CORE",
    "PROCESS_MB",
    "SESSIONS_PER_PROCESS",
    "SESSION_MB",
    "THINKING_SESSIONS_PER_CORE",
    "Hosting",
    "auto_workers",
    "available_memory_mb",
    "hosting_for",
    "parse_workers",
    "shares_processes",
    "usable_cores",
]

AUTO = "auto"
INSTANT_AGENTS = frozenset({"oracle", "noop"})
# Measured (perf/think_latency.py, docs/performance.md): the memory one more lockstep
# session adds to a process that hosts several (its peak, one session of every family and
# level, 3 to 30 drones), and a worker process before any session.
SESSION_MB = 55.0
PROCESS_MB = 100.0
MEMORY_SHARE = 0.5  # of the memory available when the run starts
# Sessions of an instant agent per core: each waits on MAVLink round trips about two thirds
# of its wall time (perf/task_spans.py), and the lossy-link tasks on MAVSDK's retries for
# seconds. The whole oracle suite on 2 cores: 6 at once 345.3 and 348.3 s (the cores 1.73
# busy), 8 at once 324.4 s (1.88), 10 at once 327.0 s (1.94, with more CPU per task).
INSTANT_SESSIONS_PER_CORE = 4
# Sessions of an agent that thinks, per core: one hosted session costs 0.9-2.6 % of a core
# while its agent thinks (3 to 30 drones, perf/idle_sessions.py) and its share of the flying
# besides. The whole suite with 2 s of thought before each call (perf/think_latency.py, 2
# cores): 63 per core kept both cores busy for good and ran slower; 16 per core left a third
# of each core idle while the sessions' chains of calls set the pace; 32 per core kept both
# busy until the last sessions, the longest first, ran out.
THINKING_SESSIONS_PER_CORE = 32
# Sessions one worker process hosts at once, at most: each holds a swarm and a MAVSDK
# instance, and processes that held 20-32 at once (MAVSDK 4.1's C++ core) found their C heap
# corrupted when they exited (glibc's "munmap_chunk(): invalid pointer", "free(): invalid
# size" or "double free", the process killed by SIGABRT): 20 of 20 runs with the suite's
# first two sessions of every family and level, whether they ran tasks or only connected,
# though not every mix did (25 three-drone sessions at once exited cleanly); none of 10 runs
# with 16-18 at once, two of them the whole suite in 4 processes of 16. So a run hosts more
# sessions at once in more processes.
SESSIONS_PER_PROCESS = 16


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity where the OS tells it)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def available_memory_mb() -> float:
    """MemAvailable from /proc/meminfo (Linux); elsewhere free pages times page size."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") / 2**20
    except (ValueError, OSError, AttributeError):
        return 4096.0


def parse_workers(text: str) -> int | str:
    """A --workers value: a whole number >= 1 or "auto"; ValueError otherwise."""
    if text.strip().lower() == AUTO:
        return AUTO
    try:
        value = int(text)
    except ValueError:
        raise ValueError(f"--workers takes a whole number >= 1 or 'auto', not {text!r}") \
            from None
    if value < 1:
        raise ValueError(f"--workers must be >= 1 (or 'auto'), got {value}")
    return value


def auto_workers(agent: str, units: int, *, cores: int | None = None,
                 memory_mb: float | None = None) -> int:
    """Sessions to host at once for `agent` over `units` units (see the module docstring)."""
    cores = max(1, cores if cores is not None else usable_cores())
    units = max(1, units)
    memory = available_memory_mb() if memory_mb is None else memory_mb
    if agent in INSTANT_AGENTS:  # a process of its own per session
        by_memory = math.floor(memory * MEMORY_SHARE / (PROCESS_MB + SESSION_MB))
        return max(1, min(units, by_memory, INSTANT_SESSIONS_PER_CORE * cores))
    by_memory = math.floor((memory * MEMORY_SHARE - PROCESS_MB * cores) / SESSION_MB)
    return max(1, min(units, by_memory, THINKING_SESSIONS_PER_CORE * cores))


@dataclass(frozen=True)
class Hosting:
    """Sessions at once, spread over processes (each hosting up to `per_process`)."""

    sessions: int
    processes: int

    @property
    def per_process(self) -> int:
        return math.ceil(self.sessions / self.processes)


def hosting_for(sessions: int, cores: int | None = None, *, shared: bool = True) -> Hosting:
    """`sessions` at once: over one process per core when processes are `shared` (fewer when
    there are fewer sessions; more when a process would host more than
    SESSIONS_PER_PROCESS), else a process each."""
    if sessions < 1:
        raise ValueError("workers must be >= 1")
    if not shared:
        return Hosting(sessions, sessions)
    cores = max(1, cores if cores is not None else usable_cores())
    return Hosting(sessions, max(min(sessions, cores),
                                 math.ceil(sessions / SESSIONS_PER_PROCESS)))


def shares_processes(agent: str) -> bool:
    """Whether a run of `agent` hosts several sessions per worker process (see above)."""
    return agent not in INSTANT_AGENTS
