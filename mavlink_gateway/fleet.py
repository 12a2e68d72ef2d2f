"""The gateway's MAVLink side: one MAVSDK instance for the whole swarm, a DroneLink each."""

from __future__ import annotations

import asyncio
import concurrent.futures
import time
from collections.abc import Sequence

from mavsdk.asyncio import ComponentType, Configuration, Mavsdk
from mavsdk.asyncio.exceptions import MavsdkConnectionError

from mavlink_gateway.drone_link import LANDED_STATE_HZ, DroneLink, DroneProfile
from mavlink_gateway.interfaces import GeoFrame
from mavlink_gateway.mavsdk_log import set_mavsdk_log

__all__ = ["FleetConnection", "FleetError"]

DISCOVERY_TIMEOUT_S = 15.0


class FleetError(RuntimeError):
    """Raised when the swarm cannot be reached or some drones never appear."""


class FleetConnection:
    """Connects to a swarm and keeps a DroneLink per expected drone.

    Use `async with await FleetConnection.connect(url, profiles, origin) as fleet:`.
    """

    def __init__(self, mavsdk: Mavsdk, drones: dict[str, DroneLink]) -> None:
        self._mavsdk = mavsdk
        self.drones = drones
        self._url = ""
        self._origin: GeoFrame | None = None
        self._landed_state_hz: float | None = LANDED_STATE_HZ

    @classmethod
    async def connect(cls, url: str, profiles: Sequence[DroneProfile], origin: GeoFrame, *,
                      timeout_s: float = DISCOVERY_TIMEOUT_S,
                      landed_state_hz: float | None = LANDED_STATE_HZ) -> FleetConnection:
        """Open `url` (e.g. ``udpin://0.0.0.0:14540``) and wait for every drone in profiles.
        `landed_state_hz`: the EXTENDED_SYS_STATE rate asked of every drone (None: its
        own)."""
        loop = asyncio.get_running_loop()
        # MAVSDK runs each blocking call on the default executor: size it for the fleet.
        loop.set_default_executor(
            concurrent.futures.ThreadPoolExecutor(max(32, 2 * len(profiles) + 8))
        )
        set_mavsdk_log()  # MAVSDK's own log lines: dropped unless this process asked for them
        mavsdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
        try:
            try:
                await mavsdk.add_any_connection(url)
            except MavsdkConnectionError as error:
                raise FleetError(f"cannot open the MAVLink connection {url!r}: {error}") from None
            drones = await _attach(mavsdk, url, profiles, origin, timeout_s, landed_state_hz)
        except BaseException:
            mavsdk.destroy()
            raise
        fleet = cls(mavsdk, drones)
        fleet._url, fleet._origin, fleet._landed_state_hz = url, origin, landed_state_hz
        return fleet

    async def attach(self, profiles: Sequence[DroneProfile], *,
                     timeout_s: float = DISCOVERY_TIMEOUT_S) -> dict[str, DroneLink]:
        """Discover more drones on the same connection (a fleet connected with few or no
        profiles, e.g. one that links a drone only once it is first commanded); the new
        DroneLinks, also added to `drones`. FleetError when one does not appear."""
        new = [p for p in profiles if p.drone_id not in self.drones]
        if not new:
            return {}
        if self._origin is None:
            raise FleetError("this fleet was not opened with FleetConnection.connect")
        found = await _attach(self._mavsdk, self._url, new, self._origin, timeout_s,
                              self._landed_state_hz)
        self.drones.update(found)
        return found

    async def detach(self, drone_id: str) -> None:
        """Forget a drone (it left the swarm): its link stops; nothing when unknown."""
        link = self.drones.pop(drone_id, None)
        if link is not None:
            await link.close()

    async def close(self) -> None:
        for link in self.drones.values():
            await link.close()
        self._mavsdk.destroy()

    async def __aenter__(self) -> FleetConnection:
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()


async def _attach(mavsdk: Mavsdk, url: str, profiles: Sequence[DroneProfile], origin: GeoFrame,
                  timeout_s: float, landed_state_hz: float | None) -> dict[str, DroneLink]:
    """Wait for every drone in profiles to appear on `mavsdk`, start a DroneLink each and
    wait for its first telemetry."""
    by_system = {p.system_id: p for p in profiles}
    found: dict[int, object] = {}
    deadline = time.monotonic() + timeout_s
    while len(found) < len(by_system):
        for system in await mavsdk.get_systems():
            sid = await system.get_system_id()
            if sid in by_system and sid not in found and await system.is_connected() \
                    and await system.has_autopilot():
                found[sid] = system
        if len(found) == len(by_system):
            break
        if time.monotonic() > deadline:
            missing = sorted(set(by_system) - set(found))
            raise FleetError(f"no autopilot answered on {url} for systems {missing}")
        await asyncio.sleep(0.05)
    drones = {p.drone_id: DroneLink(p, found[p.system_id], origin,
                                    landed_state_hz=landed_state_hz)
              for p in profiles}
    for link in drones.values():
        link.start()
    deadline = time.monotonic() + timeout_s
    while not all(link.ready for link in drones.values()):
        if time.monotonic() > deadline:
            for link in drones.values():
                await link.close()
            silent = [d for d, link in drones.items() if not link.ready]
            raise FleetError(f"no telemetry from drones {silent}")
        await asyncio.sleep(0.05)
    return drones
