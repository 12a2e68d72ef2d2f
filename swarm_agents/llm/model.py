"""The model seam of the LLM agents: what they ask a chat model and what it answers.

An agent hands a `ChatModel` the conversation so far (OpenAI chat-completions messages as
dicts) and the tools' function schemas, and gets back a `ModelReply`: the assistant message as
the model gave it (tool calls possibly malformed: reading them is the agent's business) and the
turn's token use and cost. `swarm_agents.llm.openai_model` implements it over the official `openai`
SDK for any OpenAI-compatible server; `swarm_agents.llm.scripted` in process, for tests and
examples; inspect's model plays it in `mavswarm.inspect`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

__all__ = ["ChatModel", "ModelError", "ModelReply", "Usage"]


class ModelError(RuntimeError):
    """Raised when the model backend cannot give a usable answer (after its retries)."""


@dataclass(frozen=True)
class Usage:
    """One model turn's token use (as the backend reported it) and its price."""

    prompt: int = 0
    completion: int = 0
    cost_usd: float = 0.0

    def tokens(self) -> dict[str, int]:
        """The counts as a transcript entry carries them."""
        return {"prompt": self.prompt, "completion": self.completion}


@dataclass(frozen=True)
class ModelReply:
    """The assistant message of one turn (a chat-completions message dict) and its usage."""

    message: dict[str, Any]
    usage: Usage


@runtime_checkable
class ChatModel(Protocol):
    """A chat model with tool calling, as the LLM agents use it."""

    async def complete(self, messages: Sequence[Mapping[str, Any]],
                       tools: Sequence[Mapping[str, Any]]) -> ModelReply:
        """The model's answer to `messages`, offered `tools` (OpenAI function schemas; none:
        a plain text answer is wanted). Raises `ModelError` when no usable answer comes."""
        ...

    async def close(self) -> None:
        """Let go of what the model holds (connections); it is not used afterwards."""
        ...
