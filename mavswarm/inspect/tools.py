"""The agent tools as inspect `ToolDef`s, generated from the one tool registry
(`llm_tools.registry`, itself generated from `agent_contract.AgentTools`): the same names,
descriptions and JSON schemas every other surface shows, and calls validated and run by the
registry, so a model sees and gets exactly what it would through `bench run`, REST or MCP."""

from __future__ import annotations

from typing import Any

from inspect_ai.tool import ToolDef, ToolParams

from agent_contract import AgentTools
from llm_tools.registry import ToolRegistry
from swarm_agents.llm.react import result_text

__all__ = ["tool_defs"]


def tool_defs(registry: ToolRegistry, tools: AgentTools) -> list[ToolDef]:
    """Every tool of the registry as a ToolDef acting on one task's `tools`. They run one at
    a time when inspect's own tool loop calls them (parallel=False); the swarm agent runs the
    calls of one model turn side by side itself. A result reads as `bench run`'s ReAct agent
    sends it."""
    defs = []
    for spec in registry.specs():
        defs.append(ToolDef(_executor(registry, tools, spec.name), name=spec.name,
                            description=spec.description,
                            parameters=ToolParams.model_validate(spec.input_schema),
                            parallel=False))
    return defs


def _executor(registry: ToolRegistry, tools: AgentTools, name: str) -> Any:
    async def execute(**arguments: Any) -> str:
        return result_text(await registry.call(tools, name, arguments))
    return execute
