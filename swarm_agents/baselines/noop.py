"""An agent that does nothing: the floor every other agent should beat."""

from __future__ import annotations

from agent_contract import AgentTask, AgentTools

__all__ = ["NoopAgent"]


class NoopAgent:
    """Finishes at once without touching a drone."""

    name = "noop"

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        tools.finish("nothing done")
