"""One drone as the gateway sees it: its MAVSDK plugins and a cache of its telemetry.

Every number here arrived over MAVLink (GLOBAL_POSITION_INT, HEARTBEAT, SYS_STATUS,
EXTENDED_SYS_STATE, STATUSTEXT ...); the cache is kept current by subscription tasks so a
primitive can check preconditions and wait for outcomes without a round trip.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass
from typing import Any

from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.camera import CameraAsync
from mavsdk.asyncio.plugins.mission_raw import MissionRawAsync
from mavsdk.asyncio.plugins.param import ParamAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync

from emulator.geo import GeoOrigin, wrap_heading_deg
from mavlink_gateway.outcomes import DroneState

__all__ = ["DroneLink", "DroneProfile"]

HOVER_SPEED_M_S = 0.5


@dataclass(frozen=True, slots=True)
class DroneProfile:
    """What the fleet's owner knows of a drone (not of the world): its id and limits."""

    drone_id: str
    name: str
    system_id: int
    max_altitude_m: float
    max_speed_m_s: float
    perceived_radius_m: float
    task_radius_m: float


class DroneLink:
    """MAVSDK plugins of one system plus its live telemetry."""

    def __init__(self, profile: DroneProfile, system: Any, origin: GeoOrigin) -> None:
        self.profile = profile
        self.system = system
        self.origin = origin
        self.action = ActionAsync(system)
        self.telemetry = TelemetryAsync(system)
        self.mission = MissionRawAsync(system)
        self.camera = CameraAsync(system)
        self.param = ParamAsync(system)
        self.position_m: tuple[float, float, float] | None = None
        self.velocity_m_s = (0.0, 0.0, 0.0)
        self.heading_deg = 0.0
        self.battery_pct = math.nan
        self.in_air = False
        self.landed_state = "ON_GROUND"
        self.armed = False
        self.mode = "UNKNOWN"
        self.home_m: tuple[float, float, float] | None = None
        self.mission_progress = (0, 0)
        self.status_texts: list[str] = []
        self.captures: list[Any] = []
        self.updates = 0  # telemetry messages seen; lets waits know fresh data arrived
        self._tasks: list[asyncio.Task[None]] = []

    @property
    def drone_id(self) -> str:
        return self.profile.drone_id

    # ------------------------------------------------------------ telemetry
    def start(self) -> None:
        t = self.telemetry
        follow = self._follow
        follow(t.subscribe_position(), self._on_position)
        follow(t.subscribe_velocity_ned(), self._on_velocity)
        follow(t.subscribe_heading(), lambda h: setattr(self, "heading_deg",
                                                        wrap_heading_deg(h.heading_deg)))
        follow(t.subscribe_battery(), lambda b: setattr(self, "battery_pct",
                                                        float(b.remaining_percent)))
        follow(t.subscribe_in_air(), lambda v: setattr(self, "in_air", bool(v)))
        follow(t.subscribe_landed_state(), lambda v: setattr(self, "landed_state", v.name))
        follow(t.subscribe_armed(), lambda v: setattr(self, "armed", bool(v)))
        follow(t.subscribe_flight_mode(), lambda v: setattr(self, "mode", v.name))
        follow(t.subscribe_home(), self._on_home)
        follow(t.subscribe_status_text(), lambda s: self.status_texts.append(s.text))
        follow(self.mission.subscribe_mission_progress(),
               lambda p: setattr(self, "mission_progress", (p.current, p.total)))
        follow(self.camera.subscribe_capture_info(), self.captures.append)

    def _follow(self, stream: AsyncIterator[Any], apply: Callable[[Any], None]) -> None:
        async def run() -> None:
            async for value in stream:
                apply(value)
                self.updates += 1

        self._tasks.append(asyncio.create_task(run(), name=f"telemetry-{self.drone_id}"))

    def _on_position(self, p: Any) -> None:
        x, y, z = self.origin.to_local(p.latitude_deg, p.longitude_deg, p.absolute_altitude_m)
        self.position_m = (x, y, z)

    def _on_velocity(self, v: Any) -> None:
        self.velocity_m_s = (v.east_m_s, v.north_m_s, -v.down_m_s)

    def _on_home(self, h: Any) -> None:
        self.home_m = self.origin.to_local(h.latitude_deg, h.longitude_deg,
                                           h.absolute_altitude_m)

    async def close(self) -> None:
        for task in self._tasks:
            task.cancel()
        for task in self._tasks:
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        self._tasks.clear()

    # ---------------------------------------------------------------- views
    @property
    def ready(self) -> bool:
        return self.position_m is not None and not math.isnan(self.battery_pct)

    @property
    def speed_m_s(self) -> float:
        return math.sqrt(sum(v * v for v in self.velocity_m_s))

    @property
    def flight_state(self) -> str:
        if self.landed_state == "ON_GROUND" or not self.in_air:
            return "on_ground"
        if self.landed_state == "TAKING_OFF":
            return "taking_off"
        if self.landed_state == "LANDING":
            return "landing"
        return "hovering" if self.speed_m_s < HOVER_SPEED_M_S else "flying"

    def state(self) -> DroneState:
        x, y, z = self.position_m or (math.nan, math.nan, math.nan)
        home_z = self.home_m[2] if self.home_m else 0.0
        return DroneState(
            drone=self.drone_id, x_m=x, y_m=y, altitude_m=z - home_z,
            heading_deg=self.heading_deg, battery_pct=self.battery_pct,
            flight_state=self.flight_state, armed=self.armed, mode=self.mode.lower(),
        )

    def geodetic(self, x_m: float, y_m: float, z_m: float) -> tuple[float, float, float]:
        """Local ENU (z above the origin's ground) -> latitude, longitude, altitude AMSL."""
        return self.origin.to_geodetic(x_m, y_m, z_m)
