"""Commands on `{prefix}/{session}/{drone}/services`, answered on `.../services_reply`.

A request is a JSON object `{"id": "...", "tool": "move_to", "args": {...}}`; the drone
comes from the topic. Tools are the agent tools that act on one drone, with the registry's
schemas, validation, statuses and messages (the same as REST, MCP and OpenAI tools). A
request that cannot be parsed, names an unknown drone or tool, or contradicts its topic gets
an error reply and changes nothing. Who may publish a request is the broker's business: the
bus only listens where its ACL lets operators write (see docs/mqtt.md).
"""

from __future__ import annotations

import asyncio
import inspect
import logging
import re
from collections.abc import Awaitable, Callable, Sequence
from typing import Any, Protocol

from agent_contract import AgentTools, BudgetExhausted, TaskBudget, tool_names
from llm_tools.input_limits import InputError, parse_json
from llm_tools.registry import ToolRegistry
from mqtt_bus.connection import BusConnection
from mqtt_bus.payload_types import REQUEST_ID_PATTERN, ServicesRequest
from mqtt_bus.payloads import encode
from mqtt_bus.topics import SessionTopics

__all__ = ["LINK_TOOLS", "MAX_REQUEST_BYTES", "OPERATOR_BUDGET", "CommandService",
           "CommandUnavailable", "LinkControl", "drone_tool_names"]

log = logging.getLogger("mavswarm.mqtt")

MAX_REQUEST_BYTES = 64 * 1024
OPERATOR_BUDGET = TaskBudget(tool_calls=1_000_000_000, sim_time_s=365 * 86_400.0)
"""Operators commanding over MQTT spend no agent's budget: theirs is never reached."""
_REQUEST_ID = re.compile(REQUEST_ID_PATTERN)
_KEYS = tuple(ServicesRequest.__annotations__)  # id, tool, args
LINK_TOOLS = ("get_link", "set_link")
"""Operator commands on a drone's link faults (not agent tools)."""


class LinkControl(Protocol):
    """Reads and sets a drone's link faults (emulator.services.SwarmServices); a bad
    setting raises ValueError naming the field and changes nothing."""

    def operator_vehicle_link(self, drone_id: str) -> dict[str, Any]: ...

    def operator_set_vehicle_link(self, drone_id: str, settings: object
                                  ) -> dict[str, Any]: ...


class CommandUnavailable(Exception):
    """Raised by a tools provider when a drone cannot be commanded now (the reason is
    replied, nothing changed)."""


def drone_tool_names() -> list[str]:
    """The agent tools that act on one drone (they take `drone_id`)."""
    return [name for name in tool_names()
            if "drone_id" in inspect.signature(getattr(AgentTools, name)).parameters]


def _error(request_id: object, drone: str, message: str, tool: object = None
           ) -> dict[str, Any]:
    return {"id": request_id if isinstance(request_id, str) else None, "drone": drone,
            "tool": tool if isinstance(tool, str) else None, "status": "error",
            "message": message}


class CommandService:
    """Answers the requests of one session's services topics.

    `tools_for(drone)`: the operator's tools for that drone (may raise CommandUnavailable);
    `refusal()`: why no command may run now (a benchmark task is running for an agent), or
    None; `link`: the swarm's link faults (`get_link`, `set_link`), None where the links are
    real (a bridged fleet)."""

    def __init__(self, topics: SessionTopics, connection: BusConnection,
                 drone_ids: Sequence[str],
                 tools_for: Callable[[str], Awaitable[AgentTools]], *,
                 refusal: Callable[[], str | None] | None = None,
                 link: LinkControl | None = None) -> None:
        self.topics = topics
        self.connection = connection
        self.drone_ids = tuple(drone_ids)
        self._tools_for = tools_for
        self._refusal = refusal
        self._link = link
        self.registry = ToolRegistry(drone_tool_names())
        self._tasks: set[asyncio.Task[None]] = set()
        self.handled = 0

    def incoming(self, topic: str, payload: bytes) -> None:
        """A message on a services topic (from the connection's reader): answered by a
        task of its own, so a long flight does not hold the next request back."""
        drone = self.topics.drone_of_services(topic)
        if drone is None:
            return
        task = asyncio.create_task(self._answer(drone, payload),
                                   name=f"mqtt-command-{self.topics.session}-{drone}")
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def close(self) -> None:
        for task in list(self._tasks):
            task.cancel()
        if self._tasks:
            await asyncio.gather(*self._tasks, return_exceptions=True)

    async def _answer(self, drone: str, payload: bytes) -> None:
        reply = await self.run(drone, payload)
        self.handled += 1
        self.connection.publish(self.topics.services_reply(drone), encode(reply), qos=1)

    async def run(self, drone: str, payload: bytes) -> dict[str, Any]:
        """The reply to one request."""
        request, problem = self._parse(drone, payload)
        if request is None:
            return problem
        request_id, tool, args = request
        refusal = self._refusal() if self._refusal else None
        if refusal:
            return {"id": request_id, "drone": drone, "tool": tool, "status": "rejected",
                    "message": refusal}
        if tool in LINK_TOOLS:
            return {"id": request_id, "drone": drone, "tool": tool,
                    **self._link_command(drone, tool, args)}
        try:
            tools = await self._tools_for(drone)
        except CommandUnavailable as error:
            return {"id": request_id, "drone": drone, "tool": tool, "status": "rejected",
                    "message": str(error)}
        try:
            result = await self.registry.call(tools, tool, {**args, "drone_id": drone})
        except BudgetExhausted as spent:
            result = {"status": "error", "message": str(spent)}
        return {"id": request_id, "drone": drone, "tool": tool, **result}

    def _link_command(self, drone: str, tool: str, args: dict[str, Any]) -> dict[str, Any]:
        if self._link is None:
            return {"status": "rejected", "message": f"{tool}: this fleet's links are real "
                    "radio links; link faults exist only in an emulated swarm"}
        if tool == "get_link":
            if args:
                return {"status": "error", "message": "get_link takes no args; send "
                        "\"args\": {}"}
            return {"status": "ok", "message": f"{drone}'s link",
                    "link": self._link.operator_vehicle_link(drone)}
        try:
            link = self._link.operator_set_vehicle_link(drone, args)
        except ValueError as error:
            return {"status": "error", "message": f"{error}; nothing was changed"}
        return {"status": "ok", "message": f"{drone}'s link faults set", "link": link}

    def _parse(self, drone: str, payload: bytes
               ) -> tuple[tuple[str, str, dict[str, Any]] | None, dict[str, Any]]:
        if len(payload) > MAX_REQUEST_BYTES:
            return None, _error(None, drone, f"the request is {len(payload)} bytes; at most "
                                f"{MAX_REQUEST_BYTES} are read")
        try:
            data = parse_json(payload.decode("utf-8"), "the request")
        except UnicodeDecodeError:
            return None, _error(None, drone, "the request is not UTF-8 text; send a JSON "
                                "object {\"id\", \"tool\", \"args\"}")
        except InputError as error:
            return None, _error(None, drone, f"{error}; send a JSON object "
                                "{\"id\", \"tool\", \"args\"}")
        if not isinstance(data, dict):
            return None, _error(None, drone, "the request must be a JSON object "
                                "{\"id\", \"tool\", \"args\"}")
        request_id, tool, args = data.get("id"), data.get("tool"), data.get("args", {})
        if not isinstance(request_id, str) or not _REQUEST_ID.match(request_id):
            return None, _error(None, drone, "the request needs an \"id\": 1-64 printable "
                                "ASCII characters, echoed in the reply", tool)
        unknown = sorted(k for k in data if k not in _KEYS)
        if unknown:
            return None, _error(request_id, drone, f"unknown request field {unknown[0]!r}; "
                                "fields: id, tool, args", tool)
        if drone not in self.drone_ids:
            known = ", ".join(self.drone_ids[:3]) + (" ..." if len(self.drone_ids) > 3 else "")
            return None, _error(request_id, drone, f"unknown drone {drone!r} in the topic "
                                f"(known: {known})", tool)
        if not isinstance(tool, str) or (self.registry.get(tool) is None
                                         and tool not in LINK_TOOLS):
            names = ", ".join([s.name for s in self.registry.specs()] + list(LINK_TOOLS))
            shown = tool if isinstance(tool, str) else type(tool).__name__
            return None, _error(request_id, drone, f"unknown tool {str(shown)[:40]!r}; "
                                f"tools: {names}", tool)
        if not isinstance(args, dict):
            return None, _error(request_id, drone, "\"args\" must be a JSON object", tool)
        named = args.get("drone_id", drone)
        if named != drone:
            return None, _error(request_id, drone, f"args.drone_id {str(named)[:40]!r} "
                                f"differs from the topic's drone {drone!r}", tool)
        return (request_id, tool, args), {}
