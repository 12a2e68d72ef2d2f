"""Agent tools that keep a log of their calls: name, arguments, outcome and the simulated
time each call began and ended. The benchmark stores the log next to each task's record (the
run inspector lays it on the replay's timeline), and live views read which primitive each drone
is executing and how its last one ended.

`LoggedTools` is `AgentTools` with every tool wrapped; the tools themselves, their schemas and
their outcomes are unchanged, so every surface (registry, REST, MCP, agents) calls them as
before.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable
from typing import Any

from agent_contract import AgentTools, BudgetExhausted, tool_names
from mavlink_gateway import Outcome

__all__ = ["MAX_ARG_CHARS", "LoggedTools", "ToolCall"]

MAX_ARG_CHARS = 200  # longer string arguments and messages are cut in the log
ToolCall = dict[str, Any]


def _short(value: Any) -> Any:
    if isinstance(value, str):
        return value if len(value) <= MAX_ARG_CHARS else value[:MAX_ARG_CHARS] + "..."
    if isinstance(value, list | tuple):
        return [_short(v) for v in value[:50]]
    if isinstance(value, float):
        return round(value, 3)
    return value


class LoggedTools(AgentTools):
    """AgentTools recording every call in `calls` (in the order they began)."""

    calls: list[ToolCall]
    _running: dict[str, ToolCall]
    _last: dict[str, ToolCall]

    def _log_start(self, name: str, bound: inspect.BoundArguments) -> ToolCall:
        if "calls" not in self.__dict__:
            self.calls, self._running, self._last = [], {}, {}
        args = {k: _short(v) for k, v in bound.arguments.items() if k != "self"}
        entry: ToolCall = {"i": len(self.calls), "name": name, "args": args,
                           "drone": args.get("drone_id"),
                           "t0_s": round(self._gw.services.clock_s(), 3), "t1_s": None,
                           "status": None, "message": None}
        self.calls.append(entry)
        if entry["drone"] is not None:
            self._running[str(entry["drone"])] = entry
        return entry

    def _log_end(self, entry: ToolCall, outcome: Outcome | None, error: str | None) -> None:
        entry["t1_s"] = round(self._gw.services.clock_s(), 3)
        if outcome is not None:
            entry["status"], entry["message"] = outcome.status.value, _short(outcome.message)
        else:
            entry["status"], entry["message"] = "error", _short(error or "")
        drone = entry["drone"]
        if drone is not None:
            if self._running.get(str(drone)) is entry:
                del self._running[str(drone)]
            self._last[str(drone)] = entry

    def call_log(self) -> list[ToolCall]:
        """Every call so far (a copy), in simulated start time, then drone, order and
        numbered so: calls that threads of an agent make side by side at one simulated instant
        list the same whatever order the threads' thinking let them through."""
        calls = sorted(self.__dict__.get("calls", []),
                       key=lambda c: (c["t0_s"], str(c["drone"] or ""), c["i"]))
        return [{**c, "i": k} for k, c in enumerate(calls)]

    def transcript_json(self) -> dict[str, Any]:
        """The agent's model transcript for the task's replay file (`add_transcript`: bounded
        there), with how many messages the bounds dropped; empty when the agent recorded
        none. Ordered by simulated time, then agent (a per-drone team's), each agent's own
        messages in the order it said them: the same whatever order the agents' thinking let
        them through."""
        if not self.transcript and not self.transcript_dropped:
            return {}
        ordered = sorted(self.transcript, key=lambda e: (e["t_s"], e.get("agent", "")))
        return {"transcript": [dict(e) for e in ordered],
                "transcript_dropped": self.transcript_dropped}

    def activity(self) -> dict[str, dict[str, Any]]:
        """Per drone: the tool it is executing now (or None) and how its last call ended."""
        running, last = self.__dict__.get("_running", {}), self.__dict__.get("_last", {})
        out: dict[str, dict[str, Any]] = {}
        for drone in set(running) | set(last):
            now, done = running.get(drone), last.get(drone)
            out[drone] = {
                "executing": None if now is None else {"name": now["name"], "args": now["args"],
                                                       "t0_s": now["t0_s"]},
                "last": None if done is None else {"name": done["name"],
                                                   "status": done["status"],
                                                   "message": done["message"]}}
        return out


def _wrap(name: str) -> Callable[..., Any]:
    original = getattr(AgentTools, name)
    signature = inspect.signature(original)
    if inspect.iscoroutinefunction(original):
        @functools.wraps(original)
        async def call_async(self: LoggedTools, *args: Any, **kwargs: Any) -> Outcome:
            bound = signature.bind(self, *args, **kwargs)
            entry = self._log_start(name, bound)
            try:
                outcome = await original(self, *args, **kwargs)
            except BudgetExhausted as spent:
                self._log_end(entry, None, f"budget: {spent}")
                raise
            except BaseException as error:
                self._log_end(entry, None, f"{type(error).__name__}: {error}")
                raise
            self._log_end(entry, outcome, None)
            return outcome
        return call_async

    @functools.wraps(original)
    def call(self: LoggedTools, *args: Any, **kwargs: Any) -> Outcome:
        bound = signature.bind(self, *args, **kwargs)
        entry = self._log_start(name, bound)
        try:
            outcome = original(self, *args, **kwargs)
        except BaseException as error:
            self._log_end(entry, None, f"{type(error).__name__}: {error}")
            raise
        self._log_end(entry, outcome, None)
        return outcome
    return call


for _name in tool_names():
    setattr(LoggedTools, _name, _wrap(_name))
