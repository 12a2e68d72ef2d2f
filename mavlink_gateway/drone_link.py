"""One drone as the gateway sees it: its MAVSDK plugins and a cache of its telemetry.

Every number here arrived over MAVLink (GLOBAL_POSITION_INT, HEARTBEAT, SYS_STATUS,
EXTENDED_SYS_STATE, STATUSTEXT ...); the cache is kept current by subscription tasks so a
primitive can check preconditions and wait for outcomes without a round trip.
"""

from __future__ import annotations

import asyncio
import contextlib
import enum
import json
import math
import time
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass
from typing import Any

from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.mavlink_direct import MavlinkDirectAsync
from mavsdk.asyncio.plugins.mission_raw import MissionRawAsync
from mavsdk.asyncio.plugins.param import ParamAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync

from mavlink_gateway.interfaces import GeoFrame, wrap_heading_deg
from mavlink_gateway.outcomes import DroneState
from mavlink_vocabulary import (
    OUT_OF_TASK_MESSAGES,
    FailuresCleared,
    FlightState,
    MavLandedState,
    derive_flight_state,
    parse_statustext,
)

__all__ = ["UNREACHABLE_WALL_S", "Capture", "DroneLink", "DroneProfile"]

# MAVSDK's landed-state names as MAV_LANDED_STATE (anything else: undefined)
_LANDED_STATES = {"ON_GROUND": MavLandedState.ON_GROUND, "IN_AIR": MavLandedState.IN_AIR,
                  "TAKING_OFF": MavLandedState.TAKEOFF, "LANDING": MavLandedState.LANDING}
# EXTENDED_SYS_STATE (landed state, in air) is 1 Hz by default (PX4 and the emulator): a
# take-off or landing would be seen up to a second after it ended. Asked for once per drone
# with SET_MESSAGE_INTERVAL; a vehicle that refuses keeps its default rate.
LANDED_STATE_HZ = 10.0
# The streams that arrive periodically (the others come on events): their message counts in
# `DroneLink.seen` tell a wait whether every cached value was refreshed since some moment.
PERIODIC = ("position", "velocity", "heading", "battery", "in_air", "landed_state", "armed",
            "flight_mode")
# No telemetry at all for this long (every stream is at least 0.5 Hz): the drone is
# unreachable, and its state is as last seen.
UNREACHABLE_WALL_S = 5.0


def _value_key(value: Any) -> Any:
    """A comparable form of a telemetry value (MAVSDK's types compare by identity; NaN
    fields compare equal here)."""
    fields = None if isinstance(value, enum.Enum) else getattr(value, "__dict__", None)
    if fields is None:
        return repr(value)
    return tuple((k, _value_key(v)) for k, v in sorted(fields.items()))


def _release(waiter: asyncio.Future[None]) -> None:
    if not waiter.done():
        waiter.set_result(None)


@dataclass(frozen=True, slots=True)
class Capture:
    """One CAMERA_IMAGE_CAPTURED: the photo's index and where it was taken."""

    index: int
    latitude_deg: float
    longitude_deg: float
    absolute_altitude_m: float


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

    def __init__(self, profile: DroneProfile, system: Any, origin: GeoFrame, *,
                 landed_state_hz: float | None = LANDED_STATE_HZ) -> None:
        self.profile = profile
        self._landed_state_hz = landed_state_hz
        self.system = system
        self.origin = origin
        self.action = ActionAsync(system)
        self.telemetry = TelemetryAsync(system)
        self.mission = MissionRawAsync(system)
        self.param = ParamAsync(system)
        self.direct = MavlinkDirectAsync(system)
        self.capture_sequence = 0  # the camera protocol's capture sequence number, per drone
        self.failure: str | None = None  # a failure the drone reported (OUT_OF_TASK_MESSAGES)
        self.last_update_wall_s = time.monotonic()
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
        # MISSION_CURRENT's (total, mission_state): its periodic stream says a mission is
        # complete even when the one MISSION_ITEM_REACHED of its last item was lost
        self.mission_state: tuple[int, int] = (0, 0)
        self.status_texts: list[str] = []
        # while set, a STATUSTEXT equal to one of status_texts[this:] is a repeat asked for
        # (`lockstep_wait`): not recorded again
        self.repeats_since: int | None = None
        self.texts_received = 0  # STATUSTEXTs that came, repeats included
        self.captures: list[Capture] = []  # CAMERA_IMAGE_CAPTURED as they came
        self.updates = 0  # telemetry messages seen; lets waits know fresh data arrived
        self.seen: dict[str, int] = {}  # telemetry messages seen per stream
        # per stream: how many messages in a row brought the same value as the one before
        self.repeats: dict[str, int] = {}
        self._last: dict[str, Any] = {}
        self._tasks: list[asyncio.Task[None]] = []
        self._update_waiters: list[asyncio.Future[None]] = []

    @property
    def drone_id(self) -> str:
        return self.profile.drone_id

    # ------------------------------------------------------------ telemetry
    def start(self) -> None:
        t = self.telemetry
        follow = self._follow
        follow("position", t.subscribe_position(), self._on_position)
        follow("velocity", t.subscribe_velocity_ned(), self._on_velocity)
        follow("heading", t.subscribe_heading(),
               lambda h: setattr(self, "heading_deg", wrap_heading_deg(h.heading_deg)))
        follow("battery", t.subscribe_battery(),
               lambda b: setattr(self, "battery_pct", float(b.remaining_percent)))
        follow("in_air", t.subscribe_in_air(), lambda v: setattr(self, "in_air", bool(v)))
        follow("landed_state", t.subscribe_landed_state(), self._on_landed_state)
        follow("armed", t.subscribe_armed(), lambda v: setattr(self, "armed", bool(v)))
        follow("flight_mode", t.subscribe_flight_mode(), lambda v: setattr(self, "mode", v.name))
        follow("home", t.subscribe_home(), self._on_home)
        follow("status_text", t.subscribe_status_text(), self._on_status_text)
        follow("mission_progress", self.mission.subscribe_mission_progress(),
               lambda p: setattr(self, "mission_progress", (p.current, p.total)))
        # Read straight off the link: MAVSDK's camera plugin would poll every component that
        # heartbeats for camera information several times a second, for the whole session.
        follow("capture", self.direct.subscribe_message("CAMERA_IMAGE_CAPTURED"),
               self._on_capture)
        follow("mission_current", self.direct.subscribe_message("MISSION_CURRENT"),
               self._on_mission_current)
        self._tasks.append(asyncio.create_task(self._request_rates(),
                                               name=f"telemetry-rates-{self.drone_id}"))

    async def _request_rates(self) -> None:
        if self._landed_state_hz is None:
            return
        with contextlib.suppress(Exception):  # best effort: the default rate still works
            await self.telemetry.set_rate_landed_state(self._landed_state_hz)

    def _follow(self, name: str, stream: AsyncIterator[Any], apply: Callable[[Any], None]
                ) -> None:
        async def run() -> None:
            async for value in stream:
                apply(value)
                self.last_update_wall_s = time.monotonic()
                self.updates += 1
                self.seen[name] = self.seen.get(name, 0) + 1
                value_key = _value_key(value)
                same = self._last.get(name) == value_key
                self.repeats[name] = self.repeats.get(name, 0) + 1 if same else 0
                self._last[name] = value_key
                if self._update_waiters:
                    self._wake_waiters()

        self._tasks.append(asyncio.create_task(run(), name=f"telemetry-{self.drone_id}"))

    def refreshed_since(self, mark: dict[str, int], streams: tuple[str, ...] = PERIODIC,
                        count: int = 1) -> bool:
        """True once each of `streams` brought `count` messages after `mark` (a copy of
        `seen` taken earlier)."""
        return all(self.seen.get(k, 0) >= mark.get(k, 0) + count for k in streams)

    def settled_since(self, mark: dict[str, int], streams: tuple[str, ...] = PERIODIC,
                      count: int = 2) -> bool:
        """True once each of `streams` brought `count` messages after `mark` and its last two
        messages agree: with the clock stopped, the cache then holds the state at the stop
        (a message sent before the stop but read after `mark` would differ from the next)."""
        return self.refreshed_since(mark, streams, count) and \
            all(self.repeats.get(k, 0) >= 1 for k in streams)

    def _wake_waiters(self) -> None:
        waiters, self._update_waiters = self._update_waiters, []
        for waiter in waiters:
            _release(waiter)

    async def wait_update(self, seen: int, timeout_s: float) -> None:
        """Return once a telemetry message newer than `seen` (a value of `updates`) has been
        applied, or after timeout_s, whichever comes first."""
        if self.updates != seen:
            return
        loop = asyncio.get_running_loop()
        waiter: asyncio.Future[None] = loop.create_future()
        self._update_waiters.append(waiter)
        timer = loop.call_later(timeout_s, _release, waiter)
        try:
            await waiter
        finally:
            timer.cancel()
            if waiter in self._update_waiters:
                self._update_waiters.remove(waiter)

    def _on_status_text(self, s: Any) -> None:
        self.texts_received += 1
        if self.repeats_since is not None and s.text in self.status_texts[self.repeats_since:]:
            return
        self.status_texts.append(s.text)
        message = parse_statustext(s.text)
        if isinstance(message, OUT_OF_TASK_MESSAGES) and self.failure is None:
            self.failure = s.text
        elif isinstance(message, FailuresCleared):
            self.failure = None

    def silent_for_s(self) -> float:
        """Wall seconds since the last telemetry message of any kind."""
        return time.monotonic() - self.last_update_wall_s

    def _on_landed_state(self, v: Any) -> None:
        # A vehicle that leaves the ground is armed. `armed` otherwise comes with the 1 Hz
        # HEARTBEAT, which would hold a take-off's outcome back by up to a second; the next
        # heartbeat still rules.
        if self.landed_state == "ON_GROUND" and v.name in ("TAKING_OFF", "IN_AIR"):
            self.armed = True
        self.landed_state = v.name

    def _on_capture(self, m: Any) -> None:
        with contextlib.suppress(ValueError, TypeError, KeyError, AttributeError):
            fields = json.loads(m.fields_json)
            self.captures.append(Capture(int(fields["image_index"]), int(fields["lat"]) / 1e7,
                                         int(fields["lon"]) / 1e7, int(fields["alt"]) / 1e3))

    def _on_mission_current(self, m: Any) -> None:
        with contextlib.suppress(ValueError, TypeError, KeyError, AttributeError):
            fields = json.loads(m.fields_json)
            self.mission_state = (int(fields["total"]), int(fields["mission_state"]))

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
    def reported_state(self) -> FlightState:
        """`flight_state`, or "unreachable" (no telemetry for UNREACHABLE_WALL_S) or "failed"
        (the drone reported a failure that takes it out)."""
        if self.silent_for_s() > UNREACHABLE_WALL_S:
            return FlightState.UNREACHABLE
        if self.failure is not None:
            return FlightState.FAILED
        return self.flight_state

    @property
    def flight_state(self) -> FlightState:
        """on_ground, taking_off, hovering, flying or landing, by telemetry."""
        landed = _LANDED_STATES.get(self.landed_state, MavLandedState.UNDEFINED)
        return derive_flight_state(landed, self.in_air, self.speed_m_s)

    def state(self) -> DroneState:
        x, y, z = self.position_m or (math.nan, math.nan, math.nan)
        hx, hy, home_z = self.home_m or (math.nan, math.nan, 0.0)
        return DroneState(
            drone=self.drone_id, x_m=x, y_m=y, altitude_m=z - home_z,
            heading_deg=self.heading_deg, battery_pct=self.battery_pct,
            flight_state=self.reported_state, armed=self.armed, mode=self.mode.lower(),
            home_x_m=hx, home_y_m=hy,
        )

    def geodetic(self, x_m: float, y_m: float, z_m: float) -> tuple[float, float, float]:
        """Local ENU (z above the origin's ground) -> latitude, longitude, altitude AMSL."""
        return self.origin.to_geodetic(x_m, y_m, z_m)
