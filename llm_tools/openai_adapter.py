"""OpenAI function calling: tool definitions from the registry, and tool calls read from a
chat-completion message (tolerant of what models get wrong)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from llm_tools.registry import ToolRegistry

__all__ = ["ToolCall", "openai_tools", "parse_tool_calls"]


@dataclass(frozen=True)
class ToolCall:
    id: str
    name: str
    arguments: str | Mapping[str, Any] | None


def openai_tools(registry: ToolRegistry) -> list[dict[str, Any]]:
    """The `tools` list of a chat-completions request (strict schemas)."""
    return [{"type": "function",
             "function": {"name": s.name, "description": s.description,
                          "parameters": s.input_schema}}
            for s in registry.specs()]


def parse_tool_calls(message: Mapping[str, Any]) -> list[ToolCall]:
    """Tool calls of an assistant message; entries too broken to name a tool are kept with
    an empty name (the registry answers them with an error)."""
    calls = []
    for k, raw in enumerate(message.get("tool_calls") or []):
        if not isinstance(raw, Mapping):
            calls.append(ToolCall(f"call_{k}", "", None))
            continue
        found = raw.get("function")
        function: Mapping[str, Any] = found if isinstance(found, Mapping) else {}
        calls.append(ToolCall(str(raw.get("id") or f"call_{k}"), str(function.get("name") or ""),
                              function.get("arguments")))
    return calls
