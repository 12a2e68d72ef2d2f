"""What crosses the wire in a hosted run: the task `GET /next` hands an external agent, and
the notices a unit (the process running a session) sends the driver about its tasks.

Each shape is one pydantic model; the JSON an agent reads and the payload of a unit's
``("hosted", ...)`` message are dumped from it, and the driver reads the payload back through
it, so there is no second hand-written copy.
"""

from __future__ import annotations

from enum import StrEnum

from pydantic import BaseModel, ConfigDict, Field

__all__ = ["BudgetView", "Notice", "NoticeKind", "TaskOffer", "TokenUse"]


class BudgetView(BaseModel):
    """The task's budget as the agent sees it (the same numbers an in-process agent gets)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    tool_calls: int = Field(description="tool calls the task may make")
    sim_time_s: float = Field(description="simulated seconds from the task's start")


class TaskOffer(BaseModel):
    """One task an external agent may take: what `GET {endpoint}/next` answers with."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    session: str = Field(description="the session id")
    task_id: str = Field(description="the task id within the session")
    trial: int = Field(description="which repeat of the session (--trials), from 0")
    text: str = Field(description="the instruction, in natural language")
    budget: BudgetView
    drones: list[str] = Field(description="the ids of the session's drones")
    key: str = Field(description="this task's agent key: send it as X-API-Key; it stops "
                                 "working when the task ends")
    base_url: str = Field(description="the server of this task (REST and reference routes)")
    tools_url: str = Field(description="POST {tools_url}/{tool} with the arguments as a JSON "
                                       "object; GET {tools_url} lists the tools")
    mcp_url: str = Field(description="the same tools over MCP (streamable HTTP)")


class TokenUse(BaseModel):
    """Token use an agent reports for its task (`POST {base_url}/sessions/current/tokens`),
    added up in the task's record as an in-process agent's `tools.add_tokens` is."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    prompt: int = Field(ge=0, le=10**9, description="prompt tokens of the model calls")
    completion: int = Field(ge=0, le=10**9, description="completion tokens")
    cost_usd: float = Field(0.0, ge=0.0, le=10**6, description="their price in USD")


class NoticeKind(StrEnum):
    OFFER = "offer"  # a task is ready for an agent (`offer` holds it)
    ENDED = "ended"  # the task is over (finish, budget, timeout): its key no longer works
    CLOSED = "closed"  # the unit is done: it offers no more tasks


class Notice(BaseModel):
    """A unit's message to the driver about one of its tasks (sent as ``("hosted", ...)``)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    kind: NoticeKind
    key: str = ""  # the task's key ("" for CLOSED)
    offer: TaskOffer | None = None
