"""Budget accounting for one task's tools: tool calls counted, simulated time measured from
the task's start, primitives still running cancelled at the end.

A call made after the budget is spent raises `BudgetExhausted`; a call made after `finish` is
refused with a REJECTED outcome and is not counted.
"""

from __future__ import annotations

import asyncio
import json
from collections.abc import Awaitable, Callable, Mapping
from typing import Any

from agent_contract.protocol import AgentTask, BudgetExhausted
from mavlink_gateway import Gateway, Outcome, Status
from mavlink_gateway.pacing import run_concurrently

__all__ = ["TRANSCRIPT_MAX_CHARS", "TRANSCRIPT_MAX_ENTRIES", "TRANSCRIPT_MAX_TEXT",
           "TRANSCRIPT_ROLES", "BudgetedTools"]

TRANSCRIPT_ROLES = ("system", "user", "assistant", "tool")
TRANSCRIPT_MAX_TEXT = 20_000  # characters kept of one content or one call's arguments
TRANSCRIPT_MAX_ENTRIES = 2_000  # messages kept of one task's transcript
TRANSCRIPT_MAX_CHARS = 1_000_000  # characters kept of one task's transcript in all


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
        self.transcript: list[dict[str, Any]] = []
        self.transcript_dropped = 0
        self._transcript_chars = 0

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

    def add_transcript(self, role: str, content: str, *,
                       tool_calls: list[dict[str, Any]] | None = None,
                       tokens: dict[str, int] | None = None,
                       tool_call_id: str | None = None, agent: str | None = None) -> None:
        """Record one message of the agent's model conversation, at the simulated time now:
        its role (system, user, assistant or tool), its text, the tool calls an assistant
        message makes (each {"id", "name", "arguments"}: the arguments as the model wrote them,
        in full) and the tokens of the model turn that answered ({"prompt", "completion"}).
        The benchmark stores it beside the task's replay. Bounded: a text or arguments longer
        than TRANSCRIPT_MAX_TEXT characters is cut (marked "..."); past TRANSCRIPT_MAX_ENTRIES
        messages or TRANSCRIPT_MAX_CHARS characters, messages are counted in
        `transcript_dropped` and not kept. A role not in TRANSCRIPT_ROLES, a tool call that is
        not an object, or tokens that are not counts raise ValueError (nothing is recorded)."""
        if role not in TRANSCRIPT_ROLES:
            raise ValueError(f"transcript role must be one of {', '.join(TRANSCRIPT_ROLES)}; "
                             f"got {role!r}")
        entry: dict[str, Any] = {"t_s": round(self.clock_s, 3), "role": role,
                                 "content": _cut(str(content or ""))}
        if tool_calls:
            entry["tool_calls"] = [_transcript_call(c) for c in tool_calls]
        if agent is not None:
            entry["agent"] = str(agent)
        if tool_call_id is not None:
            entry["tool_call_id"] = str(tool_call_id)
        if tokens is not None:
            entry["tokens"] = _transcript_tokens(tokens)
        size = len(entry["content"]) + sum(len(c["arguments"])
                                           for c in entry.get("tool_calls", []))
        if (len(self.transcript) >= TRANSCRIPT_MAX_ENTRIES
                or self._transcript_chars + size > TRANSCRIPT_MAX_CHARS):
            self.transcript_dropped += 1
            return
        self._transcript_chars += size
        self.transcript.append(entry)

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


def _cut(value: Any) -> str:
    """A transcript text (arguments given as an object are JSON-encoded), bounded."""
    if value is None:
        return ""
    text = value if isinstance(value, str) else json.dumps(value, default=str)
    return text if len(text) <= TRANSCRIPT_MAX_TEXT else text[:TRANSCRIPT_MAX_TEXT] + "..."


def _transcript_call(call: Any) -> dict[str, str]:
    if not isinstance(call, Mapping):
        raise ValueError('each transcript tool call must be an object {"id", "name", '
                         f'"arguments"}}; got {str(call)[:80]!r}')
    return {"id": _cut(call.get("id")), "name": _cut(call.get("name")),
            "arguments": _cut(call.get("arguments"))}


def _transcript_tokens(tokens: Any) -> dict[str, int]:
    counts = {}
    for key in ("prompt", "completion"):
        value = tokens.get(key, 0) if isinstance(tokens, Mapping) else None
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            raise ValueError('transcript tokens must be {"prompt": N, "completion": N} with '
                             f"counts of 0 or more; got {str(tokens)[:80]!r}")
        counts[key] = value
    return counts
