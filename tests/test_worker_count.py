"""Sessions at once (`--workers N|auto`): how many, over how many processes, and that a
worker process really hosts several sessions side by side."""

from __future__ import annotations

import asyncio
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from benchmark.running.backends import FOLLOWER_NICE, Handle, LocalBackend, Unit
from benchmark.running.worker_count import (
    INSTANT_SESSIONS_PER_CORE,
    PROCESS_MB,
    SESSION_MB,
    SESSIONS_PER_PROCESS,
    THINKING_SESSIONS_PER_CORE,
    auto_workers,
    hosting_for,
    parse_workers,
    shares_processes,
)

ROOT = Path(__file__).resolve().parents[1]


def test_auto_for_an_instant_agent_follows_the_cores_and_the_memory() -> None:
    plenty = 1e6
    assert auto_workers("oracle", 125, cores=2, memory_mb=plenty) == 2 * INSTANT_SESSIONS_PER_CORE
    assert auto_workers("noop", 125, cores=8, memory_mb=plenty) == 8 * INSTANT_SESSIONS_PER_CORE
    assert auto_workers("oracle", 3, cores=8, memory_mb=plenty) == 3  # never more than the units
    # a process per session: half the memory holds five of them here
    memory = 2 * 5 * (PROCESS_MB + SESSION_MB)
    assert auto_workers("oracle", 125, cores=64, memory_mb=memory) == 5
    assert auto_workers("noop", 125, cores=64, memory_mb=10.0) == 1  # at least one


def test_auto_for_a_thinking_agent_follows_the_memory_and_the_cores() -> None:
    memory = 2 * (4 * PROCESS_MB + 50 * SESSION_MB)  # half of it: 50 sessions after 4 bases
    assert auto_workers("react", 125, cores=4, memory_mb=memory) == 50  # memory bound
    assert auto_workers("external", 20, cores=4, memory_mb=memory) == 20  # the units
    assert auto_workers("pkg.mod:Agent", 125, cores=2, memory_mb=100.0) == 1  # at least one
    plenty = 1e6  # the cores bound: each session costs CPU while its agent thinks
    assert auto_workers("react", 125, cores=2, memory_mb=plenty) == 2 * THINKING_SESSIONS_PER_CORE
    assert auto_workers("external", 125, cores=1, memory_mb=plenty) == THINKING_SESSIONS_PER_CORE


def test_hosting_spreads_sessions_over_one_process_per_core() -> None:
    assert (hosting_for(6, cores=2).processes, hosting_for(6, cores=2).per_process) == (2, 3)
    assert (hosting_for(5, cores=2).processes, hosting_for(5, cores=2).per_process) == (2, 3)
    assert (hosting_for(2, cores=4).processes, hosting_for(2, cores=4).per_process) == (2, 1)
    # never more than SESSIONS_PER_PROCESS in one process: more processes instead
    most = 2 * SESSIONS_PER_PROCESS
    assert (hosting_for(most, cores=2).processes, hosting_for(most, cores=2).per_process) \
        == (2, SESSIONS_PER_PROCESS)
    assert hosting_for(most + 1, cores=2).processes == 3
    assert hosting_for(64, cores=2).per_process <= SESSIONS_PER_PROCESS
    assert hosting_for(125, cores=1).processes == -(-125 // SESSIONS_PER_PROCESS)
    assert hosting_for(6, cores=2, shared=False).processes == 6  # a process per session
    with pytest.raises(ValueError):
        hosting_for(0)


@pytest.mark.parametrize("text", ["0", "-2", "many", "1.5", ""])
def test_bad_workers_values_are_refused(text: str) -> None:
    with pytest.raises(ValueError, match="--workers"):
        parse_workers(text)
    assert parse_workers("AUTO") == "auto" and parse_workers("7") == 7


def test_the_cli_refuses_a_bad_workers_value_before_anything_runs() -> None:
    done = subprocess.run([sys.executable, "-m", "mavswarm", "bench", "run", "--workers",
                           "lots"], capture_output=True, text=True, timeout=120, cwd=ROOT,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert done.returncode == 2
    assert "--workers takes a whole number >= 1 or 'auto', not 'lots'" in done.stderr


class SleepyWork:
    """A unit that says when it starts and ends in which process, and waits between."""

    def __call__(self, unit: Unit, send: Handle) -> None:
        asyncio.run(self.hosted(unit, send))

    async def hosted(self, unit: Unit, send: Handle) -> None:
        send(("note", (os.getpid(), unit.path, "start", time.monotonic(), os.nice(0))))
        await asyncio.sleep(0.5)
        send(("note", (os.getpid(), unit.path, "end", time.monotonic())))
        if unit.path == "boom":
            raise RuntimeError("this unit fails")


def test_a_worker_process_hosts_several_units_at_once_and_survives_a_failing_one() -> None:
    messages: list[tuple[str, Any]] = []
    units = [Unit(p, 0) for p in ("a", "b", "boom", "c", "d", "e")]
    LocalBackend(4, cores=2, shared=True).run(SleepyWork(), units, messages.append)
    notes = [m[1] for m in messages if m[0] == "note"]
    errors = [m[1] for m in messages if m[0] == "error"]
    assert errors == ["boom (trial 0): RuntimeError: this unit fails"]
    assert sorted(n[1] for n in notes if n[2] == "end") == ["a", "b", "boom", "c", "d", "e"]
    pids = {n[0] for n in notes}
    assert len(pids) == 2  # at most one process per core
    overlap = {}
    for pid in pids:  # two lanes per process: units run side by side, never three
        events = sorted((n[3], n[2]) for n in notes if n[0] == pid)
        running = overlap[pid] = 0
        for _, kind in events:
            running += 1 if kind == "start" else -1
            overlap[pid] = max(overlap[pid], running)
    assert max(overlap.values()) == 2, overlap  # 6 units, 2 processes: one ran 3 or more


def test_the_head_of_the_run_order_leads_at_the_machines_priority() -> None:
    """Several hosting processes: the first hosts the run order's first units (those with the
    longest chains of calls) as it starts, the others run the rest at FOLLOWER_NICE."""
    messages: list[tuple[str, Any]] = []
    units = [Unit(p, 0) for p in ("long1", "long2", "c", "d", "e", "f")]
    LocalBackend(4, cores=2, shared=True).run(SleepyWork(), units, messages.append)
    starts = [m[1] for m in messages if m[0] == "note" and m[1][2] == "start"]
    assert sorted(s[1] for s in starts) == ["c", "d", "e", "f", "long1", "long2"]
    lead = {s[0] for s in starts if s[1].startswith("long")}
    assert len(lead) == 1  # both head units in one process, side by side at the start
    base = os.nice(0)
    for pid, path, _, _, nice in starts:
        assert nice == (base if pid in lead else min(19, base + FOLLOWER_NICE)), (path, nice)
    assert len({s[0] for s in starts}) == 2


def test_an_instant_agent_gets_a_process_per_session_a_thinking_one_shares() -> None:
    assert not shares_processes("oracle") and not shares_processes("noop")
    assert shares_processes("react") and shares_processes("external")
    messages: list[tuple[str, Any]] = []
    LocalBackend(3, cores=1).run(SleepyWork(), [Unit(p, 0) for p in "abc"], messages.append)
    notes = [m[1] for m in messages if m[0] == "note"]
    assert sorted(n[1] for n in notes if n[2] == "end") == ["a", "b", "c"]
    # An instant agent's units never share a process at once (a process that finished its
    # unit before a slow-starting neighbour took one may take the next: one at a time).
    for pid in {n[0] for n in notes}:
        running = most = 0
        for _, kind in sorted((n[3], n[2]) for n in notes if n[0] == pid):
            running += 1 if kind == "start" else -1
            most = max(most, running)
        assert most == 1, pid
