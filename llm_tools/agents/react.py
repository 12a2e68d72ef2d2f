"""The ReAct baseline: the model sees the task and the tools, and alternates reasoning with
tool calls, reading each result, until it calls `finish` or runs out of steps or tokens."""

from __future__ import annotations

import json
from typing import Any

from agent_contract import AgentTask, AgentTools
from llm_tools.agents.chat import ChatClient, ModelConfig
from llm_tools.agents.transcript import Recorder
from llm_tools.openai_adapter import ToolCall, openai_tools, parse_tool_calls
from llm_tools.registry import ToolRegistry, default_registry

__all__ = ["MAX_NUDGES", "NUDGE", "SYSTEM_PROMPT", "ReactAgent", "assistant_message",
           "task_message"]

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
    """ReAct over OpenAI-compatible chat completions."""

    name = "react"

    def __init__(self, config: ModelConfig, *, registry: ToolRegistry | None = None,
                 max_steps: int = 40, max_tokens: int = 400_000) -> None:
        self.config = config
        self.registry = registry or default_registry()
        self.max_steps = max_steps
        self.max_tokens = max_tokens

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        client = ChatClient(self.config)
        messages: list[dict[str, Any]] = [
            {"role": "system", "content": SYSTEM_PROMPT},
            {"role": "user", "content": task_message(task.text, tools.drone_ids)},
        ]
        record = Recorder(tools)
        try:
            await self._loop(client, tools, messages, record)
        finally:
            record(messages)
            await client.close()

    async def _loop(self, client: ChatClient, tools: AgentTools,
                    messages: list[dict[str, Any]], record: Recorder) -> None:
        schema = openai_tools(self.registry)
        nudges = 0
        stop = f"stopped: the budget of {self.max_steps} model turns is spent"
        for _ in range(self.max_steps):
            record(messages)
            message, usage = await client.complete(messages, schema)
            tools.add_tokens(usage["prompt"], usage["completion"],
                             client.config.cost_usd(usage))
            calls = parse_tool_calls(message)
            messages.append(assistant_message(message, calls))
            record(messages, usage)
            if calls:
                # Several calls in one answer run side by side (one thread each: drones fly
                # together); a call to a drone still busy with another is refused.
                results = await tools.concurrently(
                    *(self.registry.call(tools, c.name, c.arguments) for c in calls))
                for result in results:
                    if isinstance(result, BaseException):
                        raise result
                for call, result in zip(calls, results, strict=True):
                    messages.append({"role": "tool", "tool_call_id": call.id,
                                     "content": json.dumps(result, separators=(",", ":"))})
                record(messages)
                if tools.finished:
                    return
            elif nudges >= MAX_NUDGES:
                stop = (f"stopped: the model answered without a tool call {nudges + 1} times "
                        "(text instead of tool calls)")
                break
            else:
                nudges += 1
                messages.append({"role": "user", "content": NUDGE})
            if tools.prompt_tokens + tools.completion_tokens >= self.max_tokens:
                stop = f"stopped: the budget of {self.max_tokens} tokens is spent"
                break
        if not tools.finished:
            tools.finish(stop)


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
