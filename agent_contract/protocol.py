"""The agent protocol: what an agent receives for one task, what it may be built from, and the
one method it implements. This is the public API plug-in agents are written against
(`mavswarm bench run --agent package.module:Name`, docs/agents/plugins.md).

An agent is any object with an ``async def run(self, task: AgentTask, tools: AgentTools)``:

- `task` (`AgentTask`) holds the task's ids, its instruction text and its `TaskBudget`.
- `tools` (`agent_contract.AgentTools`) are the only way to act and to perceive: one method per
  tool (``await tools.take_off("d1", 10.0)``, ``tools.nearby("d1")``...), each returning the
  gateway's `Outcome` (``.status``, ``.message``, ``.data``, ``.to_dict()``). Flight
  primitives, `hover`, `wait` and `charge` are coroutines; reads and radio calls are plain
  methods. ``tools.drone_ids`` lists the drones, ``tools.clock_s`` is the simulated time now,
  ``tools.tool_calls`` the calls counted so far. Every call counts against the budget; once it
  is spent a call raises `BudgetExhausted`, which the agent should let through (the task then
  ends with ``sim_time_budget`` or ``tool_call_budget``).
- The task ends when `run` returns (call ``tools.finish(summary)`` first to say it is done; a
  call after `finish` is refused). An exception out of `run` ends the task as ``agent_error``
  with its message; the run goes on with the next task.
- Time: with the default lockstep clock, simulated time advances only while the agent waits on
  the world (inside a flight primitive, `hover`, `wait`, `charge`), never while it computes, so
  results do not depend on how long it thinks. To drive several drones at once, await their
  calls with ``await tools.concurrently(call_a, call_b, ...)`` (each call, or each coroutine of
  your own that makes calls, becomes its own thread of control; results or raised exceptions
  come back in order), never with `asyncio.gather` or tasks of your own: the clock would not
  wait for a thread it does not know. Blocking work (a synchronous SDK) goes through
  ``await asyncio.to_thread(...)``; never block the event loop itself.
- Tokens and cost of the agent's model: report each model call with
  ``tools.add_tokens(prompt, completion, cost_usd)``; the task's record sums them.
- The model conversation, for the run inspector: record each message with
  ``tools.add_transcript(role, content, tool_calls=[{"id", "name", "arguments"}],
  tokens={"prompt", "completion"})``; it is stored beside the task's replay, with the
  simulated time of each message.
- An agent that makes no tool call and does not return stops simulated time, so its budget
  never runs out: the benchmark stops it after ``--agent-timeout-s`` wall seconds without a
  tool call or a simulated-time step (default 600) and records ``agent_error``.

What a plug-in is built from is in `AgentOptions`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from agent_contract.tools import AgentTools

__all__ = ["Agent", "AgentOptions", "AgentTask", "BudgetExhausted", "TaskBudget"]


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
    """The task as the agent sees it: its session's id, its own id, the instruction text
    (what to do, in natural language) and the budget."""

    session_id: str
    task_id: str
    text: str
    budget: TaskBudget


@dataclass(frozen=True, slots=True)
class AgentOptions:
    """What a plug-in agent's factory receives: the run's options, for one session.

    A plug-in named by `--agent` may be an agent instance, a class or a function. A class or a
    function is called once per session and trial (once per drone with ``:per-drone``): with
    one argument, this object, when its first parameter has no default or is named
    ``options``; with no argument otherwise. It must return an agent.
    """

    agent: str
    """The agent spec as given to `--agent` (the name its records carry)."""
    session_id: str
    """The session the agent plays (its tasks come one by one to `run`)."""
    trial: int = 0
    """Which repeat of the session this is (`--trials`), from 0."""
    model: str = ""
    """`--model`, or "" (an LLM agent may then read OPENAI_MODEL)."""
    base_url: str = ""
    """`--base-url`, an OpenAI-compatible endpoint, or "" (OPENAI_BASE_URL; the key is
    always read from OPENAI_API_KEY, never passed)."""
    price_in_usd_per_mtok: float = 0.0
    """`--price-in`: USD per million prompt tokens (0: unknown), for `add_tokens`' cost."""
    price_out_usd_per_mtok: float = 0.0
    """`--price-out`: USD per million completion tokens."""
    drone_id: str | None = None
    """With ``:per-drone``: the one drone this instance plays; else None."""

    def cost_usd(self, prompt_tokens: int, completion_tokens: int) -> float:
        """The price of a model call at `--price-in` / `--price-out`."""
        return (prompt_tokens * self.price_in_usd_per_mtok
                + completion_tokens * self.price_out_usd_per_mtok) / 1e6


class BudgetExhausted(Exception):
    """Raised by a tool call once the task's tool-call or simulated-time budget is spent."""

    def __init__(self, reason: str, message: str) -> None:
        super().__init__(message)
        self.reason = reason  # "tool_call_budget" or "sim_time_budget"


class Agent(Protocol):
    """An agent: given a task and its tools, act, then call `tools.finish()`.

    Returning without calling finish also ends the task. Token use, when the agent has any,
    is reported through `tools.add_tokens`. `name` is required of the built-in agents (it
    names their records); a plug-in's records carry its `--agent` spec, so it needs none.
    """

    name: str

    async def run(self, task: AgentTask, tools: AgentTools) -> None: ...
