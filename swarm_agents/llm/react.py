"""The ReAct baseline: the model sees the task and the tools, and alternates reasoning with
tool calls, reading each result, until it calls `finish` or runs out of steps or tokens."""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any

from agent_contract import AgentTask, AgentTools
from llm_tools.openai_adapter import ToolCall, openai_tools, parse_tool_calls
from llm_tools.registry import ToolRegistry, default_registry
from swarm_agents.llm.model import ChatModel
from swarm_agents.llm.openai_model import ModelConfig, opened
from swarm_agents.llm.transcript import Recorder

__all__ = ["MAX_NUDGES", "NUDGE", "SYSTEM_PROMPT", "ReactAgent", "assistant_message",
           "react_loop", "result_text", "task_message"]

SYSTEM_PROMPT = """You command a swarm of real quadrotor drones through tools.
Coordinates are local metres: x east, y north; z is altitude above home. Headings are compass
degrees (0 north, 90 east). A drone must take off before it can move. Moves fly straight and
stop before obstacles ("blocked"): then go around with intermediate points. You only know what
the tools return: use nearby() to see what a drone senses. Think briefly, then call tools;
several drones can act in the same turn. When every part of the task is done, call finish."""

MAX_NUDGES = 2
NUDGE = "Act with the tools; call finish when the whole task is done."


def task_message(text: str, drone_ids: list[str]) -> str:
    """The user message that opens a task's conversation."""
    return f"Task: {text}\nYour drones: {', '.join(drone_ids)}."


class ReactAgent:
    """ReAct over a chat model: a `ChatModel`, or a `ModelConfig` of an OpenAI-compatible
    server (a client of the `openai` SDK opened for each run)."""

    name = "react"

    def __init__(self, model: ChatModel | ModelConfig, *, registry: ToolRegistry | None = None,
                 max_steps: int = 40, max_tokens: int = 400_000) -> None:
        self.model = model
        self.registry = registry or default_registry()
        self.max_steps = max_steps
        self.max_tokens = max_tokens

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        messages: list[dict[str, Any]] = [
            {"role": "system", "content": SYSTEM_PROMPT},
            {"role": "user", "content": task_message(task.text, tools.drone_ids)},
        ]
        record = Recorder(tools)
        try:
            async with opened(self.model) as model:
                stop = await react_loop(model, self.registry, tools, messages, record,
                                        max_steps=self.max_steps, max_tokens=self.max_tokens)
            if not tools.finished:
                tools.finish(stop or "")
        finally:
            record(messages)


async def react_loop(model: ChatModel, registry: ToolRegistry, tools: AgentTools,
                     messages: list[dict[str, Any]], record: Recorder | None = None, *,
                     max_steps: int = 40, max_tokens: int | None = None) -> str | None:
    """Model turns over `messages` (which grow: answers, tool results, nudges) until the model
    calls `finish` (None) or a reason to stop (returned: the agent's finish summary). The calls
    of one turn run side by side, one thread of control each (drones fly together; a call to a
    drone still busy with another is refused). `record`, when given, puts each message in the
    task's transcript as it comes."""
    schema = openai_tools(registry)
    nudges = 0
    for _ in range(max_steps):
        if record is not None:
            record(messages)
        reply = await model.complete(messages, schema)
        tools.add_tokens(reply.usage.prompt, reply.usage.completion, reply.usage.cost_usd)
        calls = parse_tool_calls(reply.message)
        messages.append(assistant_message(reply.message, calls))
        if record is not None:
            record(messages, reply.usage.tokens())
        if calls:
            results = await tools.concurrently(
                *(registry.call(tools, c.name, c.arguments) for c in calls))
            for result in results:
                if isinstance(result, BaseException):
                    raise result
            for call, result in zip(calls, results, strict=True):
                messages.append({"role": "tool", "tool_call_id": call.id,
                                 "content": result_text(result)})
            if record is not None:
                record(messages)
            if tools.finished:
                return None
        elif nudges >= MAX_NUDGES:
            return (f"stopped: the model answered without a tool call {nudges + 1} times "
                    "(text instead of tool calls)")
        else:
            nudges += 1
            messages.append({"role": "user", "content": NUDGE})
        if max_tokens is not None and tools.prompt_tokens + tools.completion_tokens >= max_tokens:
            return f"stopped: the budget of {max_tokens} tokens is spent"
    return f"stopped: the budget of {max_steps} model turns is spent"


def result_text(result: Mapping[str, Any]) -> str:
    """A tool's result as the model reads it."""
    return json.dumps(result, separators=(",", ":"))


def assistant_message(message: dict[str, Any], calls: list[ToolCall]) -> dict[str, Any]:
    """The assistant message as it goes back into the conversation: text content and
    well-formed tool calls whose ids are the ones the tool results answer, however malformed
    the model's own message was (a strict server refuses a conversation that is not)."""
    content = message.get("content")
    if not isinstance(content, str):
        content = "" if content is None else json.dumps(content)
    out: dict[str, Any] = {"role": "assistant", "content": content}
    if calls:
        out["tool_calls"] = [
            {"id": call.id, "type": "function",
             "function": {"name": call.name or "unnamed",
                          "arguments": call.arguments if isinstance(call.arguments, str)
                          else json.dumps(call.arguments)}}
            for call in calls]
    return out
