"""One registry of agent tools, from which every adapter (OpenAI, MCP, REST) is built.

A registry made with `batch=True` (REST and MCP) also lists the `batch` tool
(`llm_tools.batch`), whose schemas are generated from the other tools' specs.

`ToolRegistry.call` never raises: unknown tools, malformed JSON, wrong or missing arguments
and spent budgets all come back as an error result a model can act on, and nothing reaches
the gateway unless the arguments validate.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from pydantic import BaseModel

from agent_contract import AgentTools, BudgetExhausted, tool_names
from agent_contract.tools import ERROR_STATUS, RESULT_STATUSES
from llm_tools.batch import (
    BATCH,
    DESCRIPTION,
    BatchArguments,
    batch_input_schema,
    batch_output_schema,
    run_batch,
)
from llm_tools.input_limits import InputError, check_bounds, parse_json, preview
from llm_tools.schema import arguments_model, describe, model_schema, validate
from mavlink_vocabulary import FlightState

__all__ = ["OUTPUT_SCHEMA", "ToolRegistry", "ToolSpec", "default_registry", "served_registry"]

OUTPUT_SCHEMA: dict[str, Any] = {
    "type": "object",
    "properties": {
        "status": {"type": "string", "enum": list(RESULT_STATUSES)},
        "message": {"type": "string"},
        "state": {"type": "object", "description": "the drone's state after the call",
                  "properties": {"flight_state": {"type": "string",
                                                  "enum": [s.value for s in FlightState]}}},
    },
    "required": ["status", "message"],
}


@dataclass(frozen=True)
class ToolSpec:
    """One tool as models see it: generated from its `AgentTools` method."""

    name: str
    description: str
    input_schema: dict[str, Any]
    output_schema: dict[str, Any] = field(default_factory=lambda: OUTPUT_SCHEMA)
    arguments: type[BaseModel] | None = None
    """What validates the arguments (`input_schema` is generated from it, but for batch)."""


def _error(message: str) -> dict[str, Any]:
    return {"status": ERROR_STATUS, "message": message}


class ToolRegistry:
    """Tools by name, with their schemas; calls validated before they run."""

    def __init__(self, names: Sequence[str] | None = None, *, batch: bool = False) -> None:
        """The tools named (default: every agent tool), from their `AgentTools` methods;
        `batch`: and the batch tool over them."""
        self._specs: dict[str, ToolSpec] = {}
        known = tool_names()
        for name in known if names is None else names:
            if name not in known:
                raise ValueError(f"{name!r} is not an agent tool; tools: {', '.join(known)}")
            if name in self._specs:
                raise ValueError(f"two tools named {name!r}")
            method = getattr(AgentTools, name)
            summary, _ = describe(method)
            model = arguments_model(method, skip=1)
            self._specs[name] = ToolSpec(name, summary, model_schema(model), arguments=model)
        if batch:
            singles = list(self._specs.values())
            self._specs[BATCH] = ToolSpec(BATCH, DESCRIPTION, batch_input_schema(singles),
                                          batch_output_schema(OUTPUT_SCHEMA), BatchArguments)

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
        assert spec.arguments is not None, name
        values, problems = validate(arguments, spec.arguments)
        if problems:
            return _error(f"{name}: " + "; ".join(problems))
        if name == BATCH:
            singles = [n for n in self._specs if n != BATCH]
            return await run_batch(tools, values["calls"], singles,
                                   lambda tool, args: self.call(tools, tool, args))
        try:
            outcome = getattr(tools, spec.name)(**values)
            if inspect.isawaitable(outcome):
                outcome = await outcome
            return outcome.to_dict()
        except BudgetExhausted:
            raise
        except (TypeError, ValueError) as error:  # e.g. a gateway refusing an odd value
            return _error(f"{name}: {error}")


def default_registry() -> ToolRegistry:
    """Every agent tool."""
    return ToolRegistry()


def served_registry() -> ToolRegistry:
    """Every agent tool and the batch tool: what REST and MCP clients call."""
    return ToolRegistry(batch=True)
