"""Budget accounting for one task's tools: tool calls counted, simulated time measured from
the task's start, primitives still running cancelled at the end.

A call made after the budget is spent raises `BudgetExhausted`; a call made after `finish` is
refused with a REJECTED outcome and is not counted.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from typing import Any

from agent_contract.protocol import AgentTask, BudgetExhausted
from mavlink_gateway import Gateway, Outcome, Status
from mavlink_gateway.pacing import run_concurrently

__all__ = ["BudgetedTools"]


class BudgetedTools:
    """The accounting half of `AgentTools`: what every tool call is charged against."""

    def __init__(self, gateway: Gateway, task: AgentTask) -> None:
        self._gw = gateway
        self._budget = task.budget
        self._t0_s = gateway.services.clock_s()
        self._calls = 0
        self._in_flight: set[asyncio.Task[Outcome]] = set()
        self.finished = False
        self.summary = ""
        self.prompt_tokens = 0
        self.completion_tokens = 0
        self.cost_usd = 0.0
        self.spent: BudgetExhausted | None = None

    @property
    def tool_calls(self) -> int:
        return self._calls

    @property
    def sim_elapsed_s(self) -> float:
        return self._gw.services.clock_s() - self._t0_s

    @property
    def clock_s(self) -> float:
        """The simulated time now."""
        return self._gw.services.clock_s()

    @property
    def drone_ids(self) -> list[str]:
        return list(self._gw.drones)

    def add_tokens(self, prompt: int, completion: int, cost_usd: float = 0.0) -> None:
        """Token use (and its price) of the agent's model, reported in the task's record."""
        self.prompt_tokens += int(prompt)
        self.completion_tokens += int(completion)
        self.cost_usd += float(cost_usd)

    def _charge(self, name: str) -> Outcome | None:
        if self.finished:
            return Outcome(Status.REJECTED, f"{name} refused: the task is already finished")
        if self._calls >= self._budget.tool_calls:
            self.spent = BudgetExhausted(
                "tool_call_budget", f"the budget of {self._budget.tool_calls} tool calls is spent")
            raise self.spent
        if self.sim_elapsed_s >= self._budget.sim_time_s:
            self.spent = BudgetExhausted(
                "sim_time_budget",
                f"the budget of {self._budget.sim_time_s:g} simulated seconds is spent")
            raise self.spent
        self._calls += 1
        return None

    async def _call(self, name: str, make: Callable[[], Awaitable[Outcome]]) -> Outcome:
        refused = self._charge(name)
        if refused is not None:
            return refused
        task = asyncio.ensure_future(make())
        self._in_flight.add(task)
        try:
            return await asyncio.shield(task)
        finally:
            if task.done():
                self._in_flight.discard(task)

    async def concurrently(self, *calls: Awaitable[Any]) -> list[Any]:
        """Await tool calls side by side (one thread of control each, for instance one per
        drone); their results, or the exceptions they raised, in order. Use this rather than
        asyncio.gather: with a lockstep clock, time then stops for each thread from the moment
        its outcome comes until it calls its next tool, as it does for a single thread."""
        return await run_concurrently(self._gw.services, calls)

    def _sync(self, name: str, call: Callable[[], Outcome]) -> Outcome:
        refused = self._charge(name)
        return refused if refused is not None else call()

    async def close(self) -> None:
        """Cancel primitives the agent left running (the task is over)."""
        pending = [t for t in self._in_flight if not t.done()]
        for task in pending:
            task.cancel()
        if pending:
            await asyncio.gather(*pending, return_exceptions=True)
        self._in_flight.clear()
