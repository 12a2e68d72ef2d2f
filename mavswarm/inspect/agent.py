"""The default agent of the inspect tasks: the benchmark's ReAct loop (`bench run --agent
react`) with inspect's model in place of the OpenAI-compatible client.

The model gets the same system prompt, opening message, tools, results and nudges as
`ReactAgent`; the calls of one model turn run side by side, one thread of control each (so
with the lockstep clock a turn's flights share simulated time, as they do in `bench run`),
and the loop ends when the model calls `finish`, answers without a tool call three times,
spends its turns or hits one of inspect's sample limits. The conversation is the sample's
`state.messages`, so inspect's log shows it as it happened.

`InspectSolverAgent` instead lets any inspect solver play the task (``generate()``,
``basic_agent()``, a solver of one's own) with the tools in ``state.tools``; inspect's tool
loop runs the calls of one turn one after another.
"""

from __future__ import annotations

from inspect_ai.model import (
    ChatMessageSystem,
    ChatMessageTool,
    ChatMessageUser,
    Model,
    get_model,
)
from inspect_ai.solver import Generate, Solver, TaskState
from inspect_ai.tool import ToolDef
from inspect_ai.util import LimitExceededError

from agent_contract import AgentTask, AgentTools
from agents.llm.react import MAX_NUDGES, NUDGE, SYSTEM_PROMPT, task_message
from llm_tools.registry import ToolRegistry, default_registry
from mavswarm.inspect.tools import call_tool, result_text, tool_defs

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
        state, model = self.state, self.model or get_model()
        defs = tool_defs(self.registry, tools)
        state.tools = list(defs)
        try:
            state.messages = [ChatMessageSystem(content=SYSTEM_PROMPT),
                              ChatMessageUser(content=task_message(task.text, tools.drone_ids))]
            stop = await self._loop(model, defs, tools)
        except LimitExceededError as limit:  # one of inspect's sample limits
            stop = f"stopped: {limit}"
        if not tools.finished:
            tools.finish(stop or "")

    async def _loop(self, model: Model, defs: list[ToolDef], tools: AgentTools) -> str | None:
        """Model turns until `finish` (None) or a reason to stop (returned)."""
        state, nudges = self.state, 0
        for _ in range(self.max_turns):
            output = await model.generate(state.messages, tools=defs)
            state.output = output
            if output.usage is not None:
                tools.add_tokens(output.usage.input_tokens, output.usage.output_tokens)
            message = output.message
            state.messages.append(message)
            calls = message.tool_calls or []
            if calls:
                results = await tools.concurrently(
                    *(call_tool(self.registry, tools, call) for call in calls))
                for result in results:
                    if isinstance(result, BaseException):
                        raise result
                for call, result in zip(calls, results, strict=True):
                    state.messages.append(ChatMessageTool(
                        content=result_text(result), tool_call_id=call.id,
                        function=call.function))
                if tools.finished:
                    return None
            elif nudges >= MAX_NUDGES:
                return (f"stopped: the model answered without a tool call {nudges + 1} times "
                        "(text instead of tool calls)")
            else:
                nudges += 1
                state.messages.append(ChatMessageUser(content=NUDGE))
        return f"stopped: the budget of {self.max_turns} model turns is spent"


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
