"""Where a benchmark run's sessions execute: the backends behind `mavswarm bench run --backend`.

A run is a list of units, one per (session file, trial). A backend calls the same unit
function for each, wherever it runs it, and passes every message the unit sends back to the
driver's `handle` in the driver's process: ``("record", record)``, ``("error", text)`` or
``("note", text)``. The driver alone writes the results file, whatever the backend.

- ``local`` (the default): in this process with one worker, else in spawned worker processes
  on this machine: one per unit, or (`shared`, for agents that think) at most one per core,
  each hosting its share of the units side by side in one event loop
  (`benchmark/running/worker_count.py`). Needs nothing beyond mavswarm itself.
- ``ray``: as Ray tasks on a Ray cluster (`benchmark/running/ray_backend.py`), for the optional
  ``ray`` extra; Ray is imported only when this backend is asked for.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import multiprocessing
import queue as queue_module
from collections.abc import Awaitable, Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

__all__ = ["BACKENDS", "Backend", "BackendUnavailable", "Handle", "LocalBackend", "Message",
           "Unit", "UnitWork", "make_backend", "require_ray"]

BACKENDS = ("local", "ray")

Message = tuple[str, Any]
Handle = Callable[[Message], None]


@dataclass(frozen=True)
class Unit:
    """One session file for one trial, and the records already written for it (task key ->
    the end state that record carries), which the unit skips and resumes from."""

    path: str
    trial: int
    done: Mapping[str, Any] = field(default_factory=dict)


UnitWork = Callable[[Unit, Handle], None]
"""Runs one unit, sending its messages as they happen. Backends that run it elsewhere pickle
it, so it must be a module-level function (or a functools.partial of one, or an instance of a
module-level class). One that also has a `hosted(unit, handle)` coroutine method can be hosted
several units at once in one process's event loop (the local backend does so)."""
HostedWork = Callable[[Unit, Handle], Awaitable[None]]


class BackendUnavailable(ValueError):
    """Raised when a backend is asked for that this installation cannot provide."""


class Backend(Protocol):
    def run(self, work: UnitWork, units: Sequence[Unit], handle: Handle) -> None:
        """Run every unit, handing each message to `handle` in this process as it arrives.
        A unit that could not finish is reported as an ``("error", ...)`` message."""


def require_ray() -> None:
    """Raise BackendUnavailable, saying how to install it, when Ray cannot be imported."""
    try:
        import ray  # noqa: F401
    except ImportError as error:
        raise BackendUnavailable(f"the ray backend needs Ray, which cannot be imported "
                                 f"({error}): pip install 'mavswarm[ray]'") from None


def make_backend(name: str, *, workers: int, ray_address: str = "",
                 shared: bool = False) -> Backend:
    """The named backend, running at most `workers` units at once (local, `shared`: several
    in one process, see LocalBackend)."""
    if workers < 1:
        raise ValueError("workers must be >= 1")
    if name == "local":
        if ray_address:
            raise ValueError("--ray-address is for --backend ray")
        return LocalBackend(workers, shared=shared)
    if name == "ray":
        require_ray()
        from benchmark.running.ray_backend import RayBackend
        return RayBackend(workers, address=ray_address)
    raise ValueError(f"unknown backend {name!r}; choose one of {', '.join(BACKENDS)}")


@dataclass(frozen=True)
class LocalBackend:
    """Units in this process (one worker) or in spawned worker processes on this machine: a
    process per unit, or with `shared` at most one per core, each hosting several units at
    once when the work can be hosted (see UnitWork)."""

    workers: int = 1
    cores: int | None = None  # processes at most (default: this machine's cores)
    shared: bool = False  # several units per process (benchmark.running.worker_count.hosting_for)

    def run(self, work: UnitWork, units: Sequence[Unit], handle: Handle) -> None:
        from benchmark.running.worker_count import hosting_for
        if self.workers == 1:
            for unit in units:
                work(unit, handle)
            return
        hosting = hosting_for(min(self.workers, max(1, len(units))), self.cores,
                              shared=self.shared)
        hosted: HostedWork | None = getattr(work, "hosted", None)
        if hosted is None or hosting.per_process == 1:
            _run_processes(work, list(units), handle, self.workers, 1)
        else:
            _run_processes(work, list(units), handle, hosting.processes, hosting.per_process)


# Hosting several processes of units that mostly think, the first worker runs the head of the
# run order (the units whose tasks allow the longest chains of calls, which set the run's
# length: benchmark.running.run_order) at the machine's priority, and the others at this
# niceness, so that on a busy machine those chains get a core whenever they need one and the
# shorter units fill in the rest.
FOLLOWER_NICE = 10


def _worker(work: UnitWork, units: Any, results: Any, per_process: int = 1,
            head: Sequence[Unit] = (), nice: int = 0) -> None:
    import os

    if nice:
        os.nice(nice)
    if per_process > 1:
        from benchmark.running.worker_heap import return_large_blocks
        return_large_blocks()  # hosting many units: what a finished task frees leaves it
        asyncio.run(_host(work.hosted, units, results, per_process,  # type: ignore[attr-defined]
                          list(head)))
        return
    while True:
        unit = units.get()
        if unit is None:
            return
        work(unit, results.put)
        results.put(("unit_done", (unit.path, unit.trial)))


async def _host(hosted: HostedWork, units: Any, results: Any, per_process: int,
                head: list[Unit] | None = None) -> None:
    """Up to `per_process` units at once in this loop, each lane taking the next unit (from
    `head` while it lasts, then from the queue) as its last one ends, until it takes the end
    mark."""
    loop = asyncio.get_running_loop()
    head = head or []
    with concurrent.futures.ThreadPoolExecutor(per_process, "unit-queue") as takers:
        async def lane() -> None:
            while True:
                unit = head.pop(0) if head else await loop.run_in_executor(takers, units.get)
                if unit is None:
                    return
                try:
                    await hosted(unit, results.put)
                except Exception as error:  # one unit's failure never ends its neighbours
                    results.put(("error", f"{unit.path} (trial {unit.trial}): "
                                          f"{type(error).__name__}: {error}"))
                results.put(("unit_done", (unit.path, unit.trial)))

        await asyncio.gather(*(lane() for _ in range(per_process)))


def _run_processes(work: UnitWork, units: list[Unit], handle: Handle, processes: int,
                   per_process: int) -> None:
    ctx = multiprocessing.get_context("spawn")
    unit_q, result_q = ctx.Queue(), ctx.Queue()
    count = min(processes, len(units))
    # see FOLLOWER_NICE: several hosting processes, the first leads with the run order's head
    head = units[:per_process] if per_process > 1 and count > 1 else []
    for unit in units[len(head):]:
        unit_q.put(unit)
    procs = [ctx.Process(target=_worker,
                         args=(work, unit_q, result_q, per_process, head if k == 0 else [],
                               FOLLOWER_NICE if head and k > 0 else 0),
                         daemon=True, name=f"bench-worker-{k}")
             for k in range(count)]
    for p in procs:
        for _ in range(per_process):
            unit_q.put(None)
        p.start()
    remaining = len(units)
    try:
        while remaining:
            try:
                message = result_q.get(timeout=1.0)
            except queue_module.Empty:
                if not any(p.is_alive() for p in procs):
                    handle(("error", f"worker processes ended with {remaining} unit(s) "
                                     "unfinished; re-run the same command to resume"))
                    return
                continue
            if message[0] == "unit_done":
                remaining -= 1
            else:
                handle(message)
    finally:
        for p in procs:
            p.join(timeout=5.0)
            if p.is_alive():
                p.terminate()
