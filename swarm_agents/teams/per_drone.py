"""One agent per drone: a decentralized team.

Each drone gets its own agent instance, which sees only that drone's tools and perception
(`DroneView`) and coordinates with the others over the radio tools (send_message, broadcast,
read_messages, wait). The agents run side by side, each as its own thread of control, and
share the task's tool-call and simulated-time budget. The task ends when every agent has
finished; the team's summary joins theirs.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Any, cast

from agent_contract.protocol import Agent, AgentTask, BudgetExhausted
from agent_contract.tools import AgentTools, tool_names
from mavlink_gateway import Outcome, Status

__all__ = ["DroneView", "PerDroneTeam", "per_drone_task"]

_TARGETED = frozenset(
    name for name in tool_names()
    if "drone_id" in inspect.signature(getattr(AgentTools, name)).parameters)


def per_drone_task(task: AgentTask, drone_id: str, team: list[str]) -> AgentTask:
    """The task as one drone's agent gets it: the team's text and who it is."""
    others = ", ".join(d for d in team if d != drone_id) or "none"
    text = (f"{task.text}\n\nYou are the agent of drone {drone_id} only; the other drones "
            f"({others}) have agents of their own. Coordinate with them by radio: "
            "send_message, broadcast, read_messages, and wait for their answers.")
    return AgentTask(task.session_id, task.task_id, text, task.budget)


class DroneView:
    """The tools of one drone's agent over the team's `AgentTools`: calls naming another drone
    are refused, `list_drones` shows this drone only, `finish` ends this agent's part only.
    Token use is counted for this agent and for the team."""

    def __init__(self, tools: AgentTools, drone_id: str) -> None:
        self._tools = tools
        self.drone_id = drone_id
        self.finished = False
        self.summary = ""
        self.prompt_tokens = 0
        self.completion_tokens = 0

    @property
    def drone_ids(self) -> list[str]:
        return [self.drone_id]

    def add_tokens(self, prompt: int, completion: int, cost_usd: float = 0.0) -> None:
        self.prompt_tokens += int(prompt)
        self.completion_tokens += int(completion)
        self._tools.add_tokens(prompt, completion, cost_usd)

    def add_transcript(self, role: str, content: str, **fields: Any) -> None:
        """Into the team's transcript, as this drone's agent's."""
        self._tools.add_transcript(role, content, **fields, agent=self.drone_id)

    def list_drones(self) -> Outcome:
        outcome = self._tools.list_drones()
        drones = [d for d in (outcome.data or {}).get("drones", [])
                  if d.get("drone") == self.drone_id]
        if outcome.status is not Status.OK:
            return outcome
        return Outcome(Status.OK, f"{len(drones)} drones", data={"drones": drones})

    def finish(self, summary: str = "") -> Outcome:
        if self.finished:
            return Outcome(Status.REJECTED, "the task is already finished")
        self.finished = True
        self.summary = str(summary)[:2000]
        return Outcome(Status.OK, f"{self.drone_id}'s part finished")

    def __getattr__(self, name: str) -> Any:
        member = getattr(self._tools, name)
        if name not in _TARGETED:
            return member
        return self._own_drone_only(name, member)

    def _own_drone_only(self, name: str, method: Callable[..., Any]) -> Callable[..., Any]:
        def refusal(drone_id: object) -> Outcome:
            return Outcome(Status.REJECTED, f"{name} refused: you are the agent of "
                           f"{self.drone_id} and cannot command or read {drone_id!r}; ask "
                           "its agent by radio")

        if inspect.iscoroutinefunction(method):
            async def call_async(drone_id: str, *args: Any, **kwargs: Any) -> Outcome:
                if self.finished:
                    return Outcome(Status.REJECTED, f"{name} refused: your part is finished")
                if drone_id != self.drone_id:
                    return refusal(drone_id)
                return cast(Outcome, await method(drone_id, *args, **kwargs))
            return call_async

        def call(drone_id: str, *args: Any, **kwargs: Any) -> Outcome:
            if self.finished:
                return Outcome(Status.REJECTED, f"{name} refused: your part is finished")
            if drone_id != self.drone_id:
                return refusal(drone_id)
            return cast(Outcome, method(drone_id, *args, **kwargs))
        return call


class PerDroneTeam:
    """An `Agent` that runs `make(drone_id)` for every drone (see the module docstring)."""

    def __init__(self, name: str, make: Callable[[str], Agent]) -> None:
        self.name = name
        self._make = make

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        team = list(tools.drone_ids)
        views = [DroneView(tools, d) for d in team]
        agents = [self._make(d) for d in team]
        results = await tools.concurrently(
            *(agent.run(per_drone_task(task, view.drone_id, team), cast(AgentTools, view))
              for agent, view in zip(agents, views, strict=True)))
        for result in results:
            if isinstance(result, BudgetExhausted):
                raise result
        for result in results:
            if isinstance(result, BaseException):
                raise result
        if not tools.finished:
            tools.finish("; ".join(f"{v.drone_id}: {v.summary or 'no summary'}" for v in views))
