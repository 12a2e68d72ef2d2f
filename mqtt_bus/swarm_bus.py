"""A swarm of this process on the bus (`mavswarm up --mqtt`, `mavswarm serve --mqtt`).

Telemetry and events come from the swarm itself (`SwarmView`); commands go through the
gateway, over MAVLink like every other client's. `up` links the gateway to a drone the first
time it is commanded (a MAVSDK client talking to the swarm's own socket), so a swarm nobody
commands carries no gateway at all.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator, Callable

from agent_contract import AgentTask, AgentTools
from emulator.services import SwarmServices
from emulator.swarm import Swarm
from mavlink_gateway import FleetConnection, FleetError, Gateway, profiles_from_scenario
from mqtt_bus.commands import OPERATOR_BUDGET, CommandUnavailable
from mqtt_bus.payload_types import EventPayload
from mqtt_bus.radio_tap import RadioTap
from mqtt_bus.session_bus import SessionBus
from mqtt_bus.swarm_view import SwarmView
from mqtt_bus.url import BrokerUrl

__all__ = ["LinkOnCommand", "gateway_session_bus", "operator_tools", "swarm_session_bus"]

OPERATOR_TASK = "mqtt-operator"


def operator_tools(session: str, gateway: Gateway) -> AgentTools:
    """The tools commands over MQTT run with: every drone tool, on the operator's budget."""
    return AgentTools(gateway, AgentTask(session, OPERATOR_TASK, "", OPERATOR_BUDGET))


class LinkOnCommand:
    """A gateway to an in-process swarm whose drones are linked over MAVLink (MAVSDK,
    `udpout` to the swarm's socket) the first time each is commanded."""

    def __init__(self, swarm: Swarm, services: SwarmServices, session: str,
                 on_event: Callable[[EventPayload], None]) -> None:
        if swarm.ports.per_vehicle:
            raise ValueError("commands over MQTT need the shared-socket topology "
                             "(not --per-vehicle-ports)")
        scenario = swarm.fleet.scenario
        self._profiles = {p.drone_id: p for p in profiles_from_scenario(scenario)}
        self._origin = scenario.world.origin
        _host, port = swarm.endpoints[0].local_address
        self._url = f"udpout://127.0.0.1:{port}"
        self._fleet: FleetConnection | None = None
        self._lock = asyncio.Lock()
        self.gateway = Gateway({}, RadioTap(services, on_event))
        self.tools = operator_tools(session, self.gateway)

    def primitive_of(self, drone: str) -> str | None:
        return self.gateway.busy_with(drone)

    async def tools_for(self, drone: str) -> AgentTools:
        if drone in self.gateway.drones:
            return self.tools
        async with self._lock:
            try:
                if self._fleet is None:
                    self._fleet = await FleetConnection.connect(self._url, [], self._origin)
                found = await self._fleet.attach([self._profiles[drone]])
            except FleetError as error:
                raise CommandUnavailable(f"drone {drone} cannot be reached over MAVLink: "
                                         f"{error}") from None
            self.gateway.drones.update(found)
        return self.tools

    async def close(self) -> None:
        if self._fleet is not None:
            await self._fleet.close()
            self._fleet = None


@contextlib.asynccontextmanager
async def swarm_session_bus(url: BrokerUrl, session: str, swarm: Swarm, *,
                            osd_hz: float = 2.0, commands: bool = True,
                            queue_size: int = 10_000) -> AsyncIterator[SessionBus]:
    """The bus of an in-process swarm (`mavswarm up`), open while inside."""
    view = SwarmView(swarm)
    services = SwarmServices(swarm)
    link = LinkOnCommand(swarm, services, session, view.add_event) if commands else None
    if link is not None:
        view.primitive_of = link.primitive_of
    try:
        async with SessionBus(url, session, view, osd_hz=osd_hz,
                              tools_for=link.tools_for if link else None,
                              link=services, queue_size=queue_size) as bus:
            yield bus
    finally:
        if link is not None:
            await link.close()


@contextlib.asynccontextmanager
async def gateway_session_bus(url: BrokerUrl, session: str, swarm: Swarm, gateway: Gateway,
                              *, refusal: Callable[[], str | None] | None = None,
                              osd_hz: float = 2.0, services: SwarmServices | None = None
                              ) -> AsyncIterator[SessionBus]:
    """The bus of an in-process swarm that already has its gateway (`mavswarm serve`): the
    radio messages the gateway's users send are heard, commands run on the operator's
    budget unless `refusal()` names a reason not to. `services` (the swarm's, default a new
    one) answers the operator's link commands."""
    view = SwarmView(swarm, primitive_of=gateway.busy_with)
    inner = gateway.services
    gateway.services = RadioTap(inner, view.add_event)
    tools = operator_tools(session, gateway)

    async def tools_for(_drone: str) -> AgentTools:
        return tools

    try:
        async with SessionBus(url, session, view, osd_hz=osd_hz, tools_for=tools_for,
                              refusal=refusal, link=services or SwarmServices(swarm)) as bus:
            yield bus
    finally:
        gateway.services = inner
