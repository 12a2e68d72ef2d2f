"""What an agent receives for one task, and the one method it implements."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from agent_contract.tools import AgentTools

__all__ = ["Agent", "AgentTask", "BudgetExhausted", "TaskBudget"]


@dataclass(frozen=True, slots=True)
class TaskBudget:
    """Limits of one task: tool calls, and simulated seconds since the task started."""

    tool_calls: int
    sim_time_s: float

    def __post_init__(self) -> None:
        if self.tool_calls < 1:
            raise ValueError(f"tool_calls must be >= 1, got {self.tool_calls}")
        if not self.sim_time_s > 0.0:
            raise ValueError(f"sim_time_s must be > 0, got {self.sim_time_s}")


@dataclass(frozen=True, slots=True)
class AgentTask:
    """The task as the agent sees it: an id, the instruction text and the budget."""

    session_id: str
    task_id: str
    text: str
    budget: TaskBudget


class BudgetExhausted(Exception):
    """Raised by a tool call once the task's tool-call or simulated-time budget is spent."""

    def __init__(self, reason: str, message: str) -> None:
        super().__init__(message)
        self.reason = reason  # "tool_call_budget" or "sim_time_budget"


class Agent(Protocol):
    """An agent: given a task and its tools, act, then call `tools.finish()`.

    Returning without calling finish also ends the task. Token use, when the agent has any,
    is reported through `tools.add_tokens`.
    """

    name: str

    async def run(self, task: AgentTask, tools: AgentTools) -> None: ...
