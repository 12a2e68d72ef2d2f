"""`mavswarm mqtt-bridge`: any MAVLink fleet on the bus, through the gateway (MAVSDK).

The fleet is described by a session file (its drones, limits and origin) or by a count of
systems 1..N (`d1`..`dN`) with the PX4 SITL default origin. Telemetry and events are what
the vehicles report over MAVLink; commands run the same tools as everywhere else.
"""

from __future__ import annotations

import asyncio
import contextlib
import signal
from collections.abc import Sequence

from agent_contract import AgentTools
from mavlink_gateway import DroneProfile, FleetConnection, Gateway
from mavlink_gateway.interfaces import GeoFrame
from mqtt_bus.fleet_services import WallClockServices
from mqtt_bus.gateway_view import GatewayView
from mqtt_bus.session_bus import SessionBus
from mqtt_bus.swarm_bus import operator_tools
from mqtt_bus.url import BrokerUrl

__all__ = ["run_bridge", "sitl_profiles"]


def sitl_profiles(count: int) -> list[DroneProfile]:
    """Systems 1..count as d1..dN with a multicopter's usual limits."""
    if not 1 <= count <= 250:
        raise ValueError(f"--drones must be between 1 and 250, got {count}")
    return [DroneProfile(f"d{k}", f"Drone {k}", k, 120.0, 12.0, 50.0, 5.0)
            for k in range(1, count + 1)]


async def run_bridge(url: BrokerUrl, mavlink: str, profiles: Sequence[DroneProfile],
                     origin: GeoFrame, session: str, *, osd_hz: float = 2.0,
                     commands: bool = True, timeout_s: float = 30.0,
                     stop: asyncio.Event | None = None) -> None:
    """Bridge until `stop` is set (default: SIGINT or SIGTERM)."""
    if stop is None:
        stop = asyncio.Event()
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            with contextlib.suppress(NotImplementedError):
                loop.add_signal_handler(sig, stop.set)
    async with await FleetConnection.connect(mavlink, profiles, origin,
                                             timeout_s=timeout_s) as fleet:
        gateway = Gateway(fleet.drones, WallClockServices())
        tools = operator_tools(session, gateway)

        async def tools_for(_drone: str) -> AgentTools:
            return tools

        view = GatewayView(gateway.drones, primitive_of=gateway.busy_with)
        async with SessionBus(url, session, view, osd_hz=osd_hz,
                              tools_for=tools_for if commands else None) as bus:
            print(f"mavswarm: bridging {len(fleet.drones)} drones on {mavlink} to "
                  f"{url.redacted()} as session {session}", flush=True)
            await stop.wait()
            print(f"mavswarm: {bus.report()}", flush=True)

