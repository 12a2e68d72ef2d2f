"""The tools a hosted task serves, on their own: under lockstep a key runs one call at a time
(a call while another runs is rejected, nothing done), calls inside `concurrently` (a batch)
run side by side, a read from a worker thread runs in the loop's thread, and the task's end is
reported once its tools say so."""

from __future__ import annotations

import asyncio
import threading
from typing import Any

from agent_contract import BudgetExhausted
from benchmark.running.hosted.task_tools import HostedTools
from mavlink_gateway import Outcome, Status
from mavlink_gateway.pacing import Thinker, run_as, run_concurrently


class Services:
    lockstep = False

    def pin(self) -> object:
        return object()

    def unpin(self, token: object) -> None:
        pass


class FakeTools:
    """The part of AgentTools a hosted task uses: a primitive that waits for `go`, a read
    that notes its thread, finish, and a budget of three calls."""

    def __init__(self) -> None:
        self.go = asyncio.Event()
        self.finished = False
        self.spent: BudgetExhausted | None = None
        self.done: list[str] = []
        self.read_threads: list[int] = []

    async def hover(self, drone_id: str, duration_s: float) -> Outcome:
        self._charge()
        await self.go.wait()
        self.done.append(f"hover {drone_id}")
        return Outcome(Status.OK, "hovered")

    def drone_state(self, drone_id: str) -> Outcome:
        self._charge()
        self.read_threads.append(threading.get_ident())
        return Outcome(Status.OK, drone_id)

    def finish(self, summary: str = "") -> Outcome:
        self.finished = True
        return Outcome(Status.OK, "task finished")

    def _charge(self) -> None:
        if len(self.done) + len(self.read_threads) >= 3:
            self.spent = BudgetExhausted("tool_call_budget", "spent")
            raise self.spent

    async def concurrently(self, *calls: Any) -> list[Any]:
        return await run_concurrently(Services(), calls)  # as AgentTools.concurrently


def _hosted(tools: FakeTools, ends: list[str], lockstep: bool = True) -> HostedTools:
    return HostedTools(tools, None, lambda: ends.append("end"),  # type: ignore[arg-type]
                       lockstep=lockstep)


async def test_one_call_at_a_time_under_lockstep_and_side_by_side_in_a_batch() -> None:
    tools, ends = FakeTools(), list[str]()
    hosted = _hosted(tools, ends)
    first = asyncio.create_task(hosted.hover("d1", 5.0))
    await asyncio.sleep(0.01)
    second = await hosted.hover("d2", 5.0)
    read = hosted.drone_state("d2")
    assert second.status is Status.REJECTED and "one call at a time" in second.message
    assert read.status is Status.REJECTED and "hover" in read.message
    tools.go.set()
    assert (await first).status is Status.OK
    assert tools.done == ["hover d1"] and tools.read_threads == []  # nothing else ran
    tools.go.clear()
    batch = asyncio.create_task(hosted.concurrently(hosted.hover("d1", 1.0),
                                                    hosted.hover("d2", 1.0)))
    await asyncio.sleep(0.01)
    assert hosted.drone_state("d3").status is Status.REJECTED  # the batch runs
    tools.go.set()
    assert [o.status for o in await batch] == [Status.OK, Status.OK]
    assert sorted(tools.done) == ["hover d1", "hover d1", "hover d2"] and not ends


async def test_without_lockstep_calls_overlap() -> None:
    tools, ends = FakeTools(), list[str]()
    hosted = _hosted(tools, ends, lockstep=False)
    first = asyncio.create_task(hosted.hover("d1", 5.0))
    await asyncio.sleep(0.01)
    assert hosted.drone_state("d2").status is Status.OK
    tools.go.set()
    assert (await first).status is Status.OK


async def test_reads_from_worker_threads_run_in_the_loop_and_the_end_is_reported() -> None:
    tools, ends = FakeTools(), list[str]()
    hosted = _hosted(tools, ends)
    loop_thread = threading.get_ident()
    states = await asyncio.gather(*(asyncio.to_thread(hosted.drone_state, f"d{k}")
                                    for k in range(3)))
    assert [s.status for s in states] == [Status.OK] * 3
    assert tools.read_threads == [loop_thread] * 3
    try:
        await asyncio.to_thread(hosted.drone_state, "d4")
    except BudgetExhausted:
        pass
    else:
        raise AssertionError("the fourth call should find the budget spent")
    assert ends and hosted.over
    ends.clear()
    assert hosted.finish().status is Status.OK and ends == ["end"]


async def test_calls_run_as_the_episode_thread() -> None:
    """With a thinker, a request's primitive runs as it: the thinker is current inside."""
    seen: list[object] = []
    thinker = Thinker(Services())

    class Probe(FakeTools):
        async def hover(self, drone_id: str, duration_s: float) -> Outcome:
            from mavlink_gateway.pacing import current_thinker
            seen.append(current_thinker())
            return Outcome(Status.OK, "hovered")

    hosted = HostedTools(Probe(), thinker, lambda: None, lockstep=True)  # type: ignore[arg-type]
    assert (await hosted.hover("d1", 1.0)).status is Status.OK
    assert seen == [thinker]
    # inside a thread of control of its own (a batch's call), the call keeps that thread
    other = Thinker(Services())
    await run_as(other, hosted.hover("d1", 1.0))
    assert seen == [thinker, other]
