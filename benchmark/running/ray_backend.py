"""Benchmark sessions as Ray tasks on a Ray cluster (`--backend ray [--ray-address ADDR]`).

Each unit (a session file and a trial) is one Ray task that calls the same unit function the
local workers call, on whichever node Ray places it: the session's swarm, UDP ports and
gateway live on that node. The task is a Ray generator: every message the unit sends is
yielded as it is sent, and the driver takes them in the order they arrive over all running
units (`ray.wait`), so each task's record reaches the driver, which alone appends it to
results.jsonl, as the task ends. At most `workers` units run at once (each also asks Ray for
one CPU, so a cluster never holds more than it has CPUs).

A unit whose worker or node dies (node lost, worker killed, object lost) is submitted again by
the driver, up to MAX_ATTEMPTS times, with the records that already arrived marked done
(with the end states they carry): it skips those tasks and continues from the layout the last
one left, exactly as a resumed run does, so nothing is run twice and no record is written
twice. Ray's own task retries are off: Ray would replay the generator from its start.

Connection: `ray.init(address=ADDR)` (ADDR like ``HEAD_IP:6379``, or ``auto``); without an
address, Ray's rules (``RAY_ADDRESS``, a cluster `ray start` began on this machine, else a
one-node instance for this run). Session files are read on the node that runs the unit, so
custom files must exist at the same path on every node; the shipped suite lies inside the
installed package.
"""

from __future__ import annotations

import contextlib
import logging
import os
import queue
import threading
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import ray
from ray.exceptions import RayError, RayTaskError

from benchmark.running.backends import Handle, Message, Unit, UnitWork

__all__ = ["MAX_ATTEMPTS", "RayBackend", "connect", "generate_on_ray", "unit_messages"]

MAX_ATTEMPTS = 3  # runs of one unit whose worker or node died before the driver gives up
WAIT_S = 1.0  # longest block in ray.wait, so Ctrl-C is seen promptly


def connect(address: str = "") -> bool:
    """Connect this process to Ray; True when this call connected (disconnect after)."""
    if ray.is_initialized():
        return False
    ray.init(address=address or None, logging_level=logging.WARNING)
    return True


def unit_messages(work: UnitWork, unit: Unit) -> Iterator[Message]:
    """Run one unit on this node, yielding each message as the unit sends it."""
    messages: queue.Queue[Message | None] = queue.Queue()

    def run() -> None:
        try:
            work(unit, messages.put)
        except Exception as error:  # the unit function reports its own failures; a bug here
            messages.put(("error", f"{unit.path} (trial {unit.trial}): "
                                   f"{type(error).__name__}: {error}"))
        finally:
            messages.put(None)

    thread = threading.Thread(target=run, name=f"unit-{Path(unit.path).stem}", daemon=True)
    thread.start()
    while (message := messages.get()) is not None:
        yield message
    thread.join()


@dataclass
class _Running:
    unit: Unit
    attempt: int = 1
    received: dict[str, Any] = field(default_factory=dict)  # key -> end state, this run

    def resubmission(self) -> _Running:
        done = {**self.unit.done, **self.received}
        return _Running(Unit(self.unit.path, self.unit.trial, done), self.attempt + 1)


def _reason(error: BaseException) -> str:
    """The error's kind and its first sentence."""
    text = " ".join(str(error).split())
    first = text.split(". ", 1)[0][:200]
    return f"{type(error).__name__}: {first}" if first else type(error).__name__


@dataclass(frozen=True)
class RayBackend:
    """Units as Ray tasks, at most `workers` at once, on the cluster at `address`."""

    workers: int = 1
    address: str = ""

    def run(self, work: UnitWork, units: Sequence[Unit], handle: Handle) -> None:
        if not units:
            return
        connected = connect(self.address)
        try:
            self._drive(work, units, handle)
        finally:
            if connected:
                ray.shutdown()

    def _drive(self, work: UnitWork, units: Sequence[Unit], handle: Handle) -> None:
        remote = ray.remote(unit_messages).options(num_cpus=1, max_retries=0)
        # Nodes read the files: a path relative to the driver's folder means nothing there.
        pending = deque(_Running(Unit(os.path.abspath(u.path), u.trial, u.done)) for u in units)
        running: dict[Any, _Running] = {}
        while pending or running:
            while pending and len(running) < self.workers:
                run = pending.popleft()
                running[remote.remote(work, run.unit)] = run
            ready, _ = ray.wait(list(running), num_returns=1, timeout=WAIT_S)
            for stream in ready:
                self._take(stream, running, pending, handle)

    @staticmethod
    def _take(stream: Any, running: dict[Any, _Running], pending: deque[_Running],
              handle: Handle) -> None:
        """Pass on the next message of a ready unit, or settle how it ended."""
        run = running[stream]
        unit = run.unit
        try:
            kind, payload = ray.get(next(stream))
        except StopIteration:
            del running[stream]
            return
        except RayTaskError as error:  # the task's own code raised: running it again won't help
            del running[stream]
            handle(("error", f"{unit.path} (trial {unit.trial}): {_reason(error)}"))
            return
        except RayError as error:  # its worker or node died, or its output was lost
            del running[stream]
            with contextlib.suppress(RayError, ValueError):  # in case it still runs
                ray.cancel(stream, force=True)
            if run.attempt >= MAX_ATTEMPTS:
                handle(("error", f"{unit.path} (trial {unit.trial}): its Ray task failed "
                                 f"{run.attempt} times ({_reason(error)}); re-run the same "
                                 "command to resume"))
            else:
                handle(("note", f"{unit.path} (trial {unit.trial}): {_reason(error)}; running "
                                f"it again after its {len(unit.done) + len(run.received)} "
                                "recorded task(s)"))
                pending.appendleft(run.resubmission())
            return
        if kind == "record":
            key = payload["key"]
            if key in unit.done or key in run.received:
                return
            run.received[key] = payload.get("end_state")
        elif kind == "note" and run.attempt > 1:
            return  # said on the first attempt already
        handle((kind, payload))


def _generated(key: tuple[str, str, int], verify: bool) -> dict[str, Any]:
    from benchmark.running.generation import generate_session
    return generate_session(*key, verify=verify)


def generate_on_ray(keys: Sequence[tuple[str, str, int]], out_dir: Path, *, verify: bool,
                    workers: int, address: str = "",
                    on_generated: Callable[[Path], None] | None = None) -> list[Path]:
    """Generate sessions (family, level, index) as Ray tasks, at most `workers` at once; the
    driver writes each file into out_dir as it arrives. A session depends on its seed alone,
    so Ray may simply run a task again whose worker died."""
    from benchmark.authoring.generate import write_session
    connected = connect(address)
    try:
        remote = ray.remote(_generated).options(num_cpus=1, max_retries=MAX_ATTEMPTS - 1)
        pending = deque(enumerate(keys))
        running: dict[Any, int] = {}
        written: dict[int, Path] = {}
        while pending or running:
            while pending and len(running) < workers:
                index, key = pending.popleft()
                running[remote.remote(key, verify)] = index
            ready, _ = ray.wait(list(running), num_returns=1, timeout=WAIT_S)
            for ref in ready:
                index = running.pop(ref)
                path = write_session(ray.get(ref), out_dir)
                written[index] = path
                if on_generated is None:
                    print(f"generated {path}", flush=True)
                else:
                    on_generated(path)
        return [written[k] for k in sorted(written)]
    finally:
        if connected:
            ray.shutdown()
