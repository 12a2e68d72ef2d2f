"""A `ChatModel` in process that answers from a script: for tests, examples and dry runs of the
LLM agents without a model server.

The script is a list of replies, taken in order, or a function of the request (the
conversation and the tools offered) that makes each reply, so agents running side by side get
the same answers in any order. A reply is

- an assistant message (a dict in the chat-completions form; tool calls may be malformed, as
  a real model's can be),
- a list of tool calls (`tool_call(...)`: the message with those calls and no text),
- a str (a text answer without tool calls), or
- an exception (raised from `complete`, as a failing backend's `ModelError` would be).

Once a list runs out every answer calls `finish` ("script ended"). Each request is kept in
`requests`, as the wire would carry it (a JSON copy: what could not be sent fails here too).
"""

from __future__ import annotations

import asyncio
import inspect
import json
from collections.abc import Awaitable, Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, TypeAlias

from swarm_agents.llm.model import ModelReply, Usage

__all__ = ["SCRIPTED_USAGE", "Reply", "ScriptedChatModel", "ScriptedRequest", "tool_call"]

Reply: TypeAlias = Mapping[str, Any] | Sequence[Mapping[str, Any]] | str | BaseException


@dataclass(frozen=True)
class ScriptedRequest:
    """One question the model was asked: the conversation and the tools' schemas."""

    messages: list[dict[str, Any]]
    tools: list[dict[str, Any]]


Answer: TypeAlias = Callable[[ScriptedRequest], Reply | Awaitable[Reply]]


def tool_call(name: str, arguments: Any, call_id: str | None = None) -> dict[str, Any]:
    """A tool call as a model writes it; arguments given as a dict are JSON-encoded, a str is
    sent as is (malformed JSON included)."""
    args = arguments if isinstance(arguments, str) else json.dumps(arguments)
    return {"id": call_id or f"call_{name}", "type": "function",
            "function": {"name": name, "arguments": args}}


SCRIPTED_USAGE = Usage(prompt=100, completion=20)


class ScriptedChatModel:
    """Answers from a script (see the module docstring); every turn reports `usage`.

    `think_s`, when given, is awaited before each answer (seconds), like a model's latency."""

    def __init__(self, script: Iterable[Reply] | Answer = (), *,
                 usage: Usage = SCRIPTED_USAGE,
                 think_s: Callable[[], float] | None = None) -> None:
        self._answer: Answer | None = script if callable(script) else None
        self._replies: list[Reply] = [] if callable(script) else list(script)
        self.usage = usage
        self.think_s = think_s
        self.requests: list[ScriptedRequest] = []
        self.closed = False

    @property
    def remaining(self) -> int:
        """Replies of a list script not yet given."""
        return len(self._replies)

    async def complete(self, messages: Sequence[Mapping[str, Any]],
                       tools: Sequence[Mapping[str, Any]]) -> ModelReply:
        request = ScriptedRequest(json.loads(json.dumps(list(messages))),
                                  json.loads(json.dumps(list(tools))))
        self.requests.append(request)
        if self.think_s is not None:
            await asyncio.sleep(max(self.think_s(), 0.0))
        reply: Any
        if self._answer is not None:
            reply = self._answer(request)
            if inspect.isawaitable(reply):
                reply = await reply
        elif self._replies:
            reply = self._replies.pop(0)
        else:
            reply = [tool_call("finish", {"summary": "script ended"})]
        return ModelReply(_message(reply), self.usage)

    async def close(self) -> None:
        self.closed = True


def _message(reply: Reply) -> dict[str, Any]:
    if isinstance(reply, BaseException):
        raise reply
    if isinstance(reply, str):
        return {"role": "assistant", "content": reply}
    if isinstance(reply, Mapping):
        return json.loads(json.dumps({"role": "assistant", **reply}))
    if isinstance(reply, Sequence):
        return {"role": "assistant", "content": "",
                "tool_calls": json.loads(json.dumps(list(reply)))}
    raise TypeError(f"a scripted reply is a message, a list of tool calls, a str or an "
                    f"exception, not {type(reply).__name__}")
