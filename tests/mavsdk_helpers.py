"""Helpers for the MAVSDK tests: waiting on MAVSDK streams, and reading the ground truth of
the swarm they fly (`swarm.recorder`, `swarm.fleet`). System id k is vehicle "dk"."""


import asyncio
import contextlib
import inspect
import math
import time
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any

import numpy as np
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync
from mavsdk.plugins.mission_raw import MissionItem
from mavsdk.plugins.telemetry import FlightMode

from emulator.swarm import Swarm

__all__ = [
    "CAMERA_COMPONENT_ID", "FRAME_GLOBAL_RELATIVE_ALT_INT", "MAV_CMD_NAV_WAYPOINT", "Watch",
    "eventually", "first", "geodetic", "horizontal_error_m", "kinds", "max_speed_m_s",
    "take_off", "truth_pos", "watching", "waypoints_items",
]

CAMERA_COMPONENT_ID = 100
FRAME_GLOBAL_RELATIVE_ALT_INT = 6
MAV_CMD_NAV_WAYPOINT = 16


class Watch:
    """Collects every value of a MAVSDK subscription in the background."""

    def __init__(self, stream: AsyncIterator[Any]) -> None:
        self.values: list[Any] = []
        self._new = asyncio.Event()
        self._task = asyncio.create_task(self._run(stream))

    async def _run(self, stream: AsyncIterator[Any]) -> None:
        async with contextlib.aclosing(stream) as it:  # type: ignore[type-var]
            async for value in it:
                self.values.append(value)
                self._new.set()

    async def wait(self, pred: Callable[[Any], bool], timeout_s: float, what: str) -> Any:
        """The first value (already seen or arriving) for which pred holds."""
        deadline = time.monotonic() + timeout_s
        seen = 0
        while True:
            for value in self.values[seen:]:
                if pred(value):
                    return value
            seen = len(self.values)
            left = deadline - time.monotonic()
            if left <= 0:
                last = self.values[-1] if self.values else None
                raise AssertionError(f"timed out after {timeout_s} s waiting for {what}; "
                                     f"{len(self.values)} values, last {last}")
            self._new.clear()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._new.wait(), left)

    async def close(self) -> None:
        self._task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await self._task


@contextlib.asynccontextmanager
async def watching(*streams: AsyncIterator[Any]) -> AsyncIterator[Any]:
    watches = [Watch(s) for s in streams]
    await asyncio.sleep(0.01)  # let every subscription register with MAVSDK
    try:
        yield watches[0] if len(watches) == 1 else watches
    finally:
        for w in watches:
            await w.close()


async def first(stream: AsyncIterator[Any], pred: Callable[[Any], bool], timeout_s: float,
                what: str) -> Any:
    async with watching(stream) as w:
        return await w.wait(pred, timeout_s, what)


async def eventually(cond: Callable[[], bool | Awaitable[bool]], timeout_s: float,
                     what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while True:
        result = cond()
        if inspect.isawaitable(result):
            result = await result
        if result:
            return
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        await asyncio.sleep(0.02)


def truth_pos(swarm: Swarm, sysid: int) -> tuple[float, float, float]:
    """Latest recorded ENU position of system `sysid`."""
    row = swarm.recorder.trajectory(f"d{sysid}")[-1]
    return float(row[1]), float(row[2]), float(row[3])


def kinds(swarm: Swarm, sysid: int) -> list[str]:
    return [e.kind for e in swarm.recorder.events(f"d{sysid}")]


def geodetic(swarm: Swarm, x: float, y: float, z: float) -> tuple[float, float, float]:
    return swarm.fleet.world.origin.to_geodetic(x, y, z)


def horizontal_error_m(swarm: Swarm, lat: float, lon: float, x: float, y: float) -> float:
    px, py, _ = swarm.fleet.world.origin.to_local(lat, lon, 0.0)
    return math.hypot(px - x, py - y)


def max_speed_m_s(swarm: Swarm, sysid: int) -> float:
    """Largest horizontal speed between consecutive recorded samples (catches teleports)."""
    rows = swarm.recorder.trajectory(f"d{sysid}")
    dt = np.diff(rows[:, 0])
    step = np.hypot(np.diff(rows[:, 1]), np.diff(rows[:, 2]))
    return float((step[dt > 0] / dt[dt > 0]).max(initial=0.0))


async def take_off(swarm: Swarm, system: Any, sysid: int, altitude_m: float) -> None:
    """Arm, take off to `altitude_m` (via MIS_TAKEOFF_ALT) and wait until it holds there."""
    action, telemetry = ActionAsync(system), TelemetryAsync(system)
    await action.set_takeoff_altitude(altitude_m)
    await action.arm()
    await action.takeoff()
    ap = swarm.fleet.autopilots[sysid - 1]
    await eventually(lambda: ap.mode.name == "HOLD" and "takeoff_complete" in kinds(swarm, sysid),
                     10.0, f"system {sysid} to finish its takeoff")
    await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.HOLD, 5.0,
                "HOLD after takeoff")


# --------------------------------------------------------------------------------- tests


def waypoints_items(swarm: Swarm, points: list[tuple[float, float, float]]) -> list[MissionItem]:
    """NAV_WAYPOINT items, frame 6 (relative altitude), at local ENU (x, y, rel_alt)."""
    items = []
    for seq, (x, y, rel) in enumerate(points):
        lat, lon, _ = geodetic(swarm, x, y, 0.0)
        items.append(MissionItem(seq, FRAME_GLOBAL_RELATIVE_ALT_INT, MAV_CMD_NAV_WAYPOINT,
                                 int(seq == 0), 1, 0.0, 1.0, 0.0, float("nan"),
                                 round(lat * 1e7), round(lon * 1e7), rel, 0))
    return items
