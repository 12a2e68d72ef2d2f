"""One registry of agent tools, from which every adapter (OpenAI, MCP, REST) is built.

`ToolRegistry.call` never raises: unknown tools, malformed JSON, wrong or missing arguments
and spent budgets all come back as an error result a model can act on, and nothing reaches
the gateway unless the arguments validate.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from benchmark.agents import AgentTools, BudgetExhausted
from llm_tools.input_limits import InputError, check_bounds, parse_json, preview
from llm_tools.schema import describe, schema_for, validate
from llm_tools.tools import TOOL_FUNCTIONS

__all__ = ["OUTPUT_SCHEMA", "ToolRegistry", "ToolSpec", "default_registry"]

ToolFn = Callable[..., Awaitable[dict[str, Any]]]

OUTPUT_SCHEMA: dict[str, Any] = {
    "type": "object",
    "properties": {
        "status": {"type": "string",
                   "enum": ["ok", "partial", "blocked", "rejected", "timeout", "error"]},
        "message": {"type": "string"},
    },
    "required": ["status", "message"],
}


@dataclass(frozen=True)
class ToolSpec:
    name: str
    description: str
    input_schema: dict[str, Any]
    fn: ToolFn


def _error(message: str) -> dict[str, Any]:
    return {"status": "error", "message": message}


class ToolRegistry:
    """Tools by name, with their schemas; calls validated before they run."""

    def __init__(self, functions: Sequence[ToolFn]) -> None:
        self._specs: dict[str, ToolSpec] = {}
        for fn in functions:
            summary, _ = describe(fn)
            spec = ToolSpec(fn.__name__, summary, schema_for(fn), fn)
            if spec.name in self._specs:
                raise ValueError(f"two tools named {spec.name!r}")
            self._specs[spec.name] = spec

    def specs(self) -> list[ToolSpec]:
        return list(self._specs.values())

    def get(self, name: str) -> ToolSpec | None:
        return self._specs.get(name)

    async def call(self, tools: AgentTools, name: str, arguments: str | Mapping[str, Any] | None
                   ) -> dict[str, Any]:
        """Run a tool for a model: the result dict, or an error result. Raises only
        BudgetExhausted (the task is over)."""
        spec = self._specs.get(name) if isinstance(name, str) else None
        if spec is None:
            known = ", ".join(self._specs)
            return _error(f"unknown tool {preview(name)}; available tools: {known}")
        try:
            if isinstance(arguments, str):
                arguments = parse_json(arguments.strip() or "{}", "the arguments text")
            else:
                check_bounds(arguments)
        except InputError as error:
            hint = "; send a JSON object" if "JSON" in error.problem else ""
            return _error(f"{name}: {error}{hint}")
        values, problems = validate(arguments, spec.input_schema)
        if problems:
            return _error(f"{name}: " + "; ".join(problems))
        try:
            return await spec.fn(tools, **values)
        except BudgetExhausted:
            raise
        except (TypeError, ValueError) as error:  # e.g. a gateway refusing an odd value
            return _error(f"{name}: {error}")


def default_registry() -> ToolRegistry:
    """The agent-side primitives."""
    return ToolRegistry(TOOL_FUNCTIONS)
