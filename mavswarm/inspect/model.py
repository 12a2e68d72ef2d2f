"""inspect's model as the `ChatModel` of the built-in LLM agents (`swarm_agents.llm`), so the
inspect tasks run the benchmark's own ReAct loop rather than a copy of it.

The conversation is mirrored into the sample's ``state.messages`` as inspect's chat messages
(each model answer as inspect gave it, the agent's other messages as they are added), so
inspect's log shows it as it happened and inspect's sample limits apply to it; a limit reached
raises inspect's `LimitExceededError` out of `complete` or `sync`.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import Any

from inspect_ai.model import (
    ChatMessage,
    ChatMessageAssistant,
    ChatMessageSystem,
    ChatMessageTool,
    ChatMessageUser,
    Model,
)
from inspect_ai.solver import TaskState
from inspect_ai.tool import ToolCall, ToolDef

from swarm_agents.llm import ModelReply, Usage

__all__ = ["InspectChatModel"]


class InspectChatModel:
    """A `ChatModel` over inspect's `model` for one sample: the agent's conversation (a list
    that only grows, one assistant message after each answer) is mirrored into
    ``state.messages``; a turn that offers tools offers inspect's `tools` (generated from the
    same registry as the agent's schemas)."""

    def __init__(self, model: Model, state: TaskState, tools: Sequence[ToolDef]) -> None:
        self.model = model
        self.state = state
        self.tools = list(tools)
        self._mirrored = 0
        self._functions: dict[str, str] = {}  # tool call id -> tool name

    def sync(self, messages: Sequence[Mapping[str, Any]]) -> None:
        """Add the conversation's messages not yet in ``state.messages``."""
        for message in messages[self._mirrored:]:
            self.state.messages.append(self._inspect_message(message))
            self._mirrored += 1

    async def complete(self, messages: Sequence[Mapping[str, Any]],
                       tools: Sequence[Mapping[str, Any]]) -> ModelReply:
        self.sync(messages)
        output = await self.model.generate(self.state.messages,
                                           tools=self.tools if tools else [])
        self.state.output = output
        answer = output.message
        self.state.messages.append(answer)
        self._mirrored += 1  # the agent's copy of this answer is in state.messages already
        calls = answer.tool_calls or []
        self._functions.update({c.id: c.function for c in calls})
        message: dict[str, Any] = {"role": "assistant", "content": answer.text}
        if calls:
            message["tool_calls"] = [_openai_call(c) for c in calls]
        usage = output.usage
        return ModelReply(message, Usage(usage.input_tokens, usage.output_tokens)
                          if usage is not None else Usage())

    async def close(self) -> None:
        """Nothing to let go: inspect owns its model."""

    def _inspect_message(self, message: Mapping[str, Any]) -> ChatMessage:
        role, content = message.get("role"), str(message.get("content") or "")
        if role == "system":
            return ChatMessageSystem(content=content)
        if role == "tool":
            call_id = str(message.get("tool_call_id", ""))
            return ChatMessageTool(content=content, tool_call_id=call_id,
                                   function=self._functions.get(call_id))
        if role == "assistant":
            return ChatMessageAssistant(content=content)
        return ChatMessageUser(content=content)


def _openai_call(call: ToolCall) -> dict[str, Any]:
    """An inspect tool call as a chat-completions one; arguments inspect could not read are
    passed on as the text of its complaint, which the tool registry refuses as not JSON."""
    arguments = (f"unreadable arguments ({call.parse_error})" if call.parse_error is not None
                 else json.dumps(call.arguments))
    return {"id": call.id, "type": "function",
            "function": {"name": call.function, "arguments": arguments}}
