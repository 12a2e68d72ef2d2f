"""The gateway's MAVLink side: one MAVSDK instance for the whole swarm, a DroneLink each."""

from __future__ import annotations

import asyncio
import concurrent.futures
import time
import weakref
from collections.abc import Callable, Sequence
from typing import Any

from mavsdk.asyncio import ComponentType, Configuration, Mavsdk
from mavsdk.asyncio.exceptions import MavsdkConnectionError

from mavlink_gateway.drone_link import LANDED_STATE_HZ, DroneLink, DroneProfile
from mavlink_gateway.interfaces import GeoFrame
from mavlink_gateway.mavsdk_log import set_mavsdk_log

__all__ = ["FleetConnection", "FleetError"]

DISCOVERY_TIMEOUT_S = 15.0
# How long close() waits for MAVSDK calls still running on worker threads (a command's own
# retries end within seconds) before it destroys MAVSDK.
CALLS_DRAIN_S = 30.0
# A drone whose first telemetry has not come is asked for it again this often (`refresh`).
ASK_AGAIN_S = 0.2


_MAVSDK_MODULES = frozenset({"mavsdk"})


class _CallPool(concurrent.futures.ThreadPoolExecutor):
    """The loop's default executor while fleets are open on it: MAVSDK's asyncio binding runs
    every blocking call on it. It knows which MAVSDK calls are still running (not the other
    work of the loop, a server's, say), so a fleet can let them end before MAVSDK is destroyed
    under them (a primitive cancelled or timed out leaves its call running on a worker
    thread)."""

    def __init__(self, workers: int) -> None:
        super().__init__(workers, thread_name_prefix="mavsdk-call")
        self.workers = workers
        self._running: set[concurrent.futures.Future[Any]] = set()

    def submit(self, fn: Callable[..., Any], /, *args: Any,
               **kwargs: Any) -> concurrent.futures.Future[Any]:
        future = super().submit(fn, *args, **kwargs)
        if getattr(fn, "__module__", None) in _MAVSDK_MODULES or \
                str(getattr(fn, "__module__", "")).startswith("mavsdk."):
            self._running.add(future)
            future.add_done_callback(self._running.discard)
        return future

    async def drain(self, timeout_s: float) -> None:
        """Wait until every MAVSDK call submitted so far has returned (at most
        `timeout_s`)."""
        running = [asyncio.wrap_future(f) for f in list(self._running)]
        if running:
            await asyncio.wait(running, timeout=timeout_s)


_call_pools: weakref.WeakKeyDictionary[asyncio.AbstractEventLoop, _CallPool] = (
    weakref.WeakKeyDictionary()
)
# Drones of the fleets open on each loop: a loop that hosts several sessions sizes its call
# pool for all of them together.
_open_drones: weakref.WeakKeyDictionary[asyncio.AbstractEventLoop, int] = (
    weakref.WeakKeyDictionary()
)


def _call_pool(loop: asyncio.AbstractEventLoop, workers: int) -> _CallPool:
    """The loop's call pool, installed as its default executor (one per loop, enlarged by
    replacing it when a bigger fleet connects; the one replaced ends once idle)."""
    pool = _call_pools.get(loop)
    if pool is None or pool.workers < workers:
        if pool is not None:
            pool.shutdown(wait=False)
        pool = _CallPool(workers)
        loop.set_default_executor(pool)
        _call_pools[loop] = pool
    return pool


class FleetError(RuntimeError):
    """Raised when the swarm cannot be reached or some drones never appear."""


class FleetConnection:
    """Connects to a swarm and keeps a DroneLink per expected drone.

    Use `async with await FleetConnection.connect(url, profiles, origin) as fleet:`.
    """

    def __init__(self, mavsdk: Mavsdk, drones: dict[str, DroneLink],
                 calls: _CallPool | None = None) -> None:
        self._mavsdk = mavsdk
        self._calls = calls
        self.drones = drones
        self._url = ""
        self._origin: GeoFrame | None = None
        self._landed_state_hz: float | None = LANDED_STATE_HZ
        self._refresh: Callable[[str], None] | None = None
        self._counted = 0  # this fleet's drones in _open_drones

    @classmethod
    async def connect(cls, url: str, profiles: Sequence[DroneProfile], origin: GeoFrame, *,
                      timeout_s: float = DISCOVERY_TIMEOUT_S,
                      landed_state_hz: float | None = LANDED_STATE_HZ,
                      refresh: Callable[[str], None] | None = None) -> FleetConnection:
        """Open `url` (e.g. ``udpin://0.0.0.0:14540``) and wait for every drone in profiles.
        `landed_state_hz`: the EXTENDED_SYS_STATE rate asked of every drone (None: its
        own). `refresh`: asks the world for a drone's whole telemetry at once (a lockstep
        swarm in this process, whose streams carry only changes), used while a drone's first
        telemetry is awaited."""
        # MAVSDK runs each blocking call on the default executor: size it for the fleet.
        loop = asyncio.get_running_loop()
        _open_drones[loop] = _open_drones.get(loop, 0) + len(profiles)
        calls = _call_pool(loop, max(32, 2 * _open_drones[loop] + 8))
        set_mavsdk_log()  # MAVSDK's own log lines: dropped unless this process asked for them
        mavsdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
        try:
            try:
                await mavsdk.add_any_connection(url)
            except MavsdkConnectionError as error:
                raise FleetError(f"cannot open the MAVLink connection {url!r}: {error}") from None
            drones = await _attach(mavsdk, url, profiles, origin, timeout_s, landed_state_hz,
                                   refresh)
        except BaseException:
            _open_drones[loop] -= len(profiles)
            await calls.drain(CALLS_DRAIN_S)
            mavsdk.destroy()
            raise
        fleet = cls(mavsdk, drones, calls)
        fleet._counted = len(profiles)
        fleet._url, fleet._origin, fleet._landed_state_hz = url, origin, landed_state_hz
        fleet._refresh = refresh
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
                              self._landed_state_hz, self._refresh)
        self.drones.update(found)
        return found

    async def detach(self, drone_id: str) -> None:
        """Forget a drone (it left the swarm): its link stops; nothing when unknown."""
        link = self.drones.pop(drone_id, None)
        if link is not None:
            await link.close()

    async def close(self) -> None:
        """End every DroneLink's subscriptions, let the MAVSDK calls still running on worker
        threads return, then destroy MAVSDK (its threads, sockets and every plugin)."""
        for link in self.drones.values():
            await link.close()
        loop = asyncio.get_running_loop()
        if self._counted:
            _open_drones[loop] = _open_drones.get(loop, 0) - self._counted
            self._counted = 0
        current = _call_pools.get(loop)
        for pool in {p for p in (self._calls, current) if p is not None}:
            await pool.drain(CALLS_DRAIN_S)
        self._mavsdk.destroy()

    async def __aenter__(self) -> FleetConnection:
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()


async def _attach(mavsdk: Mavsdk, url: str, profiles: Sequence[DroneProfile], origin: GeoFrame,
                  timeout_s: float, landed_state_hz: float | None,
                  refresh: Callable[[str], None] | None = None) -> dict[str, DroneLink]:
    """Wait for every drone in profiles to appear on `mavsdk`, start a DroneLink each and
    wait for its first telemetry (asked of `refresh` every ASK_AGAIN_S, if given)."""
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
    deadline, ask_at = time.monotonic() + timeout_s, time.monotonic()
    while not all(link.ready for link in drones.values()):
        if refresh is not None and time.monotonic() >= ask_at:
            ask_at = time.monotonic() + ASK_AGAIN_S
            for drone_id, link in drones.items():
                if not link.ready:
                    refresh(drone_id)
        if time.monotonic() > deadline:
            for link in drones.values():
                await link.close()
            silent = [d for d, link in drones.items() if not link.ready]
            raise FleetError(f"no telemetry from drones {silent}")
        await asyncio.sleep(0.02 if refresh is not None else 0.05)
    return drones
