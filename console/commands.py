"""Hands-on commands from the console: an operator picks a drone and tells it to take off, fly
to a clicked point, hover, land or return home. Each command is a call of the agent tool of
that name through the same registry every other surface uses (argument checks, outcomes and
refusals included), on tools of its own with a budget no one reaches, over a MAVLink gateway.

`up --web` has no gateway of its own: the commander opens one (MAVSDK, `udpout` to the swarm's
socket) on the first command, so a swarm nobody commands pays nothing for it.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Awaitable, Callable, Mapping
from typing import Any

from agent_contract import AgentTask, TaskBudget
from benchmark.tool_log import LoggedTools
from llm_tools.registry import ToolRegistry, default_registry
from mavlink_gateway import Gateway

__all__ = ["COMMANDS", "Commander"]

COMMANDS = ("take_off", "move_to", "hover", "land", "return_home", "change_altitude")
_BUDGET = TaskBudget(tool_calls=1_000_000_000, sim_time_s=1e12)

GatewayFactory = Callable[[], Awaitable[Gateway]]


class Commander:
    """Runs hands-on commands on one swarm's drones through the agent tools."""

    def __init__(self, session_id: str, gateway: Gateway | GatewayFactory,
                 registry: ToolRegistry | None = None) -> None:
        self.session_id = session_id
        self._registry = registry or default_registry()
        self._gateway = gateway if isinstance(gateway, Gateway) else None
        self._factory = None if isinstance(gateway, Gateway) else gateway
        self._tools: LoggedTools | None = None
        self._lock = asyncio.Lock()

    async def _ready_tools(self) -> LoggedTools:
        async with self._lock:
            if self._tools is None:
                if self._gateway is None:
                    assert self._factory is not None
                    self._gateway = await self._factory()
                task = AgentTask(self.session_id, "console", "commands from the web console",
                                 _BUDGET)
                self._tools = LoggedTools(self._gateway, task)
            return self._tools

    async def run(self, drone_id: str, tool: str, args: Mapping[str, Any]) -> dict[str, Any]:
        """The tool's result (`status`, `message`, ...); a tool that is not a console command
        is refused with the list of those that are, and nothing is sent."""
        if tool not in COMMANDS:
            return {"status": "error", "message": f"{tool!r} is not a console command; "
                                                  f"commands: {', '.join(COMMANDS)}"}
        if not isinstance(args, Mapping):
            return {"status": "error", "message": "args must be a JSON object"}
        tools = await self._ready_tools()
        return await self._registry.call(tools, tool, {**args, "drone_id": drone_id})

    def activity(self) -> dict[str, dict[str, Any]]:
        return {} if self._tools is None else self._tools.activity()

    async def aclose(self) -> None:
        if self._tools is not None:
            with contextlib.suppress(Exception):
                await self._tools.close()
