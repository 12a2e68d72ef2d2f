"""Recording an LLM agent's conversation in its task's transcript (`AgentTools.add_transcript`):
each message as the model sees it, at the simulated time it was sent or answered, with the
tool calls in full and the tokens of each model turn."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from agent_contract import AgentTools

__all__ = ["Recorder", "record_messages", "unrecorded_from"]


class Recorder:
    """Records one growing conversation: each call records the messages added since."""

    def __init__(self, tools: AgentTools) -> None:
        self.tools = tools
        self.recorded = 0

    def __call__(self, messages: Sequence[Mapping[str, Any]],
                 tokens: Mapping[str, int] | None = None) -> None:
        self.recorded = record_messages(self.tools, messages, self.recorded, tokens)


def record_messages(tools: AgentTools, messages: Sequence[Mapping[str, Any]], start: int,
                    tokens: Mapping[str, int] | None = None) -> int:
    """Record `messages[start:]`; `tokens` (the turn's usage) go with the last one when it is
    the model's answer. Returns how many messages are recorded now (the next `start`)."""
    for k in range(start, len(messages)):
        message = messages[k]
        role = str(message.get("role", ""))
        content = message.get("content")
        calls = [{"id": c.get("id", ""), "name": c.get("function", {}).get("name", ""),
                  "arguments": c.get("function", {}).get("arguments", "")}
                 for c in message.get("tool_calls") or [] if isinstance(c, Mapping)]
        last_answer = k == len(messages) - 1 and role == "assistant"
        tools.add_transcript(role, "" if content is None else str(content),
                             tool_calls=calls or None,
                             tokens=dict(tokens) if tokens is not None and last_answer else None,
                             tool_call_id=(str(message["tool_call_id"])
                                           if message.get("tool_call_id") is not None else None))
    return len(messages)


def unrecorded_from(messages: Sequence[Mapping[str, Any]]) -> int:
    """Where the messages not yet recorded start in a conversation whose every model answer
    was recorded as it came: after its last assistant message."""
    for k in range(len(messages) - 1, -1, -1):
        if messages[k].get("role") == "assistant":
            return k + 1
    return 0
