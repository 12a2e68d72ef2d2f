"""The default agent of the inspect tasks: the benchmark's ReAct loop (`bench run --agent
react`, `swarm_agents.llm.react.react_loop`) thinking with inspect's model (`InspectChatModel`).

The model gets the same system prompt, opening message, tools, results and nudges as
`ReactAgent`; the calls of one model turn run side by side, one thread of control each (so
with the lockstep clock a turn's flights share simulated time, as they do in `bench run`),
and the loop ends when the model calls `finish`, answers without a tool call three times,
spends its turns or hits one of inspect's sample limits. The conversation is mirrored into the
sample's `state.messages`, so inspect's log shows it as it happened.

`InspectSolverAgent` instead lets any inspect solver play the task (``generate()``,
``basic_agent()``, a solver of one's own) with the tools in ``state.tools``; inspect's tool
loop runs the calls of one turn one after another.
"""

from __future__ import annotations

from typing import Any

from inspect_ai.model import ChatMessageSystem, ChatMessageUser, Model, get_model
from inspect_ai.solver import Generate, Solver, TaskState
from inspect_ai.util import LimitExceededError

from agent_contract import AgentTask, AgentTools
from llm_tools.registry import ToolRegistry, default_registry
from mavswarm.inspect.model import InspectChatModel
from mavswarm.inspect.tools import tool_defs
from swarm_agents.llm.react import SYSTEM_PROMPT, react_loop, task_message

__all__ = ["InspectReactAgent", "InspectSolverAgent"]


class InspectReactAgent:
    """A mavswarm `Agent` (run(task, tools)) that thinks with inspect's model for one sample."""

    name = "react"

    def __init__(self, state: TaskState, *, model: Model | None = None, max_turns: int = 40,
                 registry: ToolRegistry | None = None) -> None:
        if max_turns < 1:
            raise ValueError(f"max_turns must be >= 1, got {max_turns}")
        self.state = state
        self.model = model
        self.max_turns = max_turns
        self.registry = registry or default_registry()

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        defs = tool_defs(self.registry, tools)
        self.state.tools = list(defs)
        model = InspectChatModel(self.model or get_model(), self.state, defs)
        messages: list[dict[str, Any]] = [
            {"role": "system", "content": SYSTEM_PROMPT},
            {"role": "user", "content": task_message(task.text, tools.drone_ids)}]
        try:
            self.state.messages = []
            stop = await react_loop(model, self.registry, tools, messages,
                                    max_steps=self.max_turns)
            model.sync(messages)  # the last tool results
        except LimitExceededError as limit:  # one of inspect's sample limits
            stop = f"stopped: {limit}"
        if not tools.finished:
            tools.finish(stop or "")


class InspectSolverAgent:
    """A mavswarm `Agent` that lets an inspect solver play one sample's task with the agent
    tools as ``state.tools`` (generated from the registry, one call at a time)."""

    name = "inspect"

    def __init__(self, state: TaskState, solver: Solver, generate: Generate, *,
                 registry: ToolRegistry | None = None) -> None:
        self.state = state
        self.solver = solver
        self.generate = generate
        self.registry = registry or default_registry()

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        state = self.state
        state.tools = list(tool_defs(self.registry, tools))
        stop = "stopped: the solver ended without calling finish"
        try:
            state.messages = [ChatMessageSystem(content=SYSTEM_PROMPT),
                              ChatMessageUser(content=task_message(task.text, tools.drone_ids))]
            await self.solver(state, self.generate)
        except LimitExceededError as limit:  # one of inspect's sample limits
            stop = f"stopped: {limit}"
        if not tools.finished:
            tools.finish(stop)
