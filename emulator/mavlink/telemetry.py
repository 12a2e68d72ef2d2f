"""Telemetry of many vehicles at once: each stream's payloads built from the fleet arrays.

The batched counterpart of `emulator.mavlink.messages`: for a message id and the indices
of the vehicles due, `FleetTelemetry.part` computes every field as that module does for one
vehicle (the same arithmetic in the same order, with Python's `math` for the
transcendental functions so no last-bit difference creeps in) and returns payload records
for `emulator.mavlink.frames.frame_batch`. The per-vehicle sequence numbers live here, in
one array per component, and the vehicles' encoders share them.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from emulator.flight.battery import BATTERY_CRITICAL, BATTERY_EMERGENCY
from emulator.flight.fleet import Fleet
from emulator.flight.modes import FlightMode
from emulator.mavlink import messages as msgs
from emulator.mavlink.camera import CAMERA_COMPONENT_ID, MAV_AUTOPILOT_INVALID, MAV_TYPE_CAMERA
from emulator.mavlink.codec import mavlink
from emulator.mavlink.frames import FramePart, MessageLayout
from emulator.mavlink.imu import highres_imu_fields
from emulator.mavlink.streams import CAMERA_HEARTBEAT
from emulator.networks import VEHICLES_PER_NETWORK
from mavlink_vocabulary import MavState

__all__ = ["BATCHED_STREAMS", "FleetTelemetry"]

AUTOPILOT_COMPONENT_ID = 1
_RAD_TO_DEG = 180.0 / math.pi
_DEG_TO_RAD = math.pi / 180.0
_PRESENT = msgs.SENSORS | msgs.PREARM_CHECK
_BASE_MODE = msgs.MODE_FLAG_CUSTOM | msgs.MODE_FLAG_STABILIZE | msgs.MODE_FLAG_GUIDED
_CHARGE_STATE = np.array([1, 2, 3, 4], dtype=np.uint8)  # by battery level; charging: 7

_LAYOUTS = {
    0: MessageLayout.of(mavlink.MAVLink_heartbeat_message),
    1: MessageLayout.of(mavlink.MAVLink_sys_status_message),
    245: MessageLayout.of(mavlink.MAVLink_extended_sys_state_message),
    33: MessageLayout.of(mavlink.MAVLink_global_position_int_message),
    32: MessageLayout.of(mavlink.MAVLink_local_position_ned_message),
    30: MessageLayout.of(mavlink.MAVLink_attitude_message),
    24: MessageLayout.of(mavlink.MAVLink_gps_raw_int_message),
    74: MessageLayout.of(mavlink.MAVLink_vfr_hud_message),
    42: MessageLayout.of(mavlink.MAVLink_mission_current_message),
    147: MessageLayout.of(mavlink.MAVLink_battery_status_message),
    242: MessageLayout.of(mavlink.MAVLink_home_position_message),
    105: MessageLayout.of(mavlink.MAVLink_highres_imu_message),
}
_LAYOUTS[CAMERA_HEARTBEAT] = _LAYOUTS[0]
BATCHED_STREAMS: frozenset[int] = frozenset(_LAYOUTS)


def _rint(x: np.ndarray) -> np.ndarray:
    """Python's round() to an integer (half to even) of every element."""
    return np.rint(x).astype(np.int64)


def _trunc(x: np.ndarray) -> np.ndarray:
    """Python's int() of every element."""
    return np.trunc(x).astype(np.int64)


class FleetTelemetry:
    """Builds telemetry payloads for any subset of a fleet's vehicles."""

    def __init__(self, fleet: Fleet) -> None:
        self.fleet = fleet
        n = fleet.n
        self.system_ids = (np.arange(n) % VEHICLES_PER_NETWORK + 1).astype(np.uint8)
        # The next sequence number of each vehicle's autopilot and camera component.
        self.sequences = {AUTOPILOT_COMPONENT_ID: np.zeros(n, dtype=np.uint8),
                          CAMERA_COMPONENT_ID: np.zeros(n, dtype=np.uint8)}
        self._builders: dict[int, Callable[[np.ndarray], Sequence[object]]] = {
            0: self._heartbeat, 1: self._sys_status, 245: self._extended_sys_state,
            33: self._global_position_int, 32: self._local_position_ned, 30: self._attitude,
            24: self._gps_raw_int, 74: self._vfr_hud, 42: self._mission_current,
            147: self._battery_status, 242: self._home_position,
            105: lambda ks: highres_imu_fields(self.fleet, ks),
            CAMERA_HEARTBEAT: self._camera_heartbeat,
        }
        # per vehicle: the heading last seen by ATTITUDE, its cos, sin and wrapped radians
        self._trig: tuple[np.ndarray, ...] | None = None

    def part(self, msg_id: int, ks: np.ndarray) -> FramePart:
        """Message `msg_id` of vehicles `ks` (distinct indices), taking their next sequence
        numbers."""
        layout = _LAYOUTS[msg_id]
        component = CAMERA_COMPONENT_ID if msg_id == CAMERA_HEARTBEAT else AUTOPILOT_COMPONENT_ID
        records = layout.records(len(ks), self._builders[msg_id](ks))
        seq = self.sequences[component]
        taken = seq[ks]
        seq[ks] = taken + np.uint8(1)  # wraps at 256
        return FramePart(layout, records, self.system_ids[ks], component, taken)

    # ----------------------------------------------------------------- helpers
    def _time_boot_ms(self) -> int:
        return int(self.fleet.now_s * 1000.0) & 0xFFFFFFFF

    def _geo(self, x: np.ndarray, y: np.ndarray, z: np.ndarray):
        origin = self.fleet.world.origin
        east_per_rad, north_per_rad = origin.metres_per_rad
        lat = origin.latitude_deg + (y / north_per_rad) * _RAD_TO_DEG
        lon = origin.longitude_deg + (x / east_per_rad) * _RAD_TO_DEG
        alt = origin.altitude_amsl_m + z
        return _rint(lat * 1e7), _rint(lon * 1e7), _rint(alt * 1000.0)

    def _homes(self, ks: np.ndarray) -> np.ndarray:
        aps = self.fleet.autopilots
        return np.array([aps[k].home_m for k in ks.tolist()], dtype=float).reshape(-1, 3)

    def _voltage_mv(self, ks: np.ndarray) -> np.ndarray:
        aps = self.fleet.autopilots
        params = [aps[k].params for k in ks.tolist()]
        empty = np.array([p["BAT_V_EMPTY"] for p in params], dtype=float)
        full = np.array([p["BAT_V_CHARGED"] for p in params], dtype=float)
        cells = np.array([p["BAT_N_CELLS"] for p in params], dtype=float)
        pct = np.minimum(np.maximum(self.fleet.bat.pct[ks], 0.0), 100.0)
        cell = empty + (full - empty) * pct / 100.0
        return _trunc(cell * cells * 1000.0)

    # ---------------------------------------------------------------- messages
    def _heartbeat(self, ks: np.ndarray) -> Sequence[object]:
        f = self.fleet
        aps = f.autopilots
        modes = [aps[k].mode for k in ks.tolist()]
        armed = f.armed[ks]
        base = np.where([m is not FlightMode.OFFBOARD for m in modes],
                        _BASE_MODE | msgs.MODE_FLAG_AUTO, _BASE_MODE)
        base = base | np.where(armed, msgs.MODE_FLAG_ARMED, 0)
        level = f.bat.level[ks]
        state = np.where(armed, msgs.STATE_ACTIVE, msgs.STATE_STANDBY)
        state = np.where(level == BATTERY_CRITICAL, msgs.STATE_CRITICAL, state)
        state = np.where(level == BATTERY_EMERGENCY, msgs.STATE_EMERGENCY, state)
        custom = [m.custom_mode for m in modes]
        return (msgs.MAV_TYPE_QUADROTOR, msgs.MAV_AUTOPILOT_PX4, base, custom, state,
                msgs.MAVLINK_VERSION)

    def _camera_heartbeat(self, ks: np.ndarray) -> Sequence[object]:
        # the vehicle's mode, as the camera's own heartbeat says (see messages.component_mode)
        aps = self.fleet.autopilots
        custom = [aps[k].mode.custom_mode for k in ks.tolist()]
        return (MAV_TYPE_CAMERA, MAV_AUTOPILOT_INVALID, msgs.MODE_FLAG_CUSTOM, custom,
                MavState.ACTIVE, msgs.MAVLINK_VERSION)

    def _sys_status(self, ks: np.ndarray) -> Sequence[object]:
        f = self.fleet
        health = np.where(f.bat.level[ks] < BATTERY_CRITICAL,
                          msgs.SENSORS | msgs.PREARM_CHECK, msgs.SENSORS)
        return (_PRESENT, _PRESENT, health, 150, self._voltage_mv(ks), -1,
                _trunc(f.bat.pct[ks]), 0, 0, 0, 0, 0, 0)

    def _battery_status(self, ks: np.ndarray) -> Sequence[object]:
        f = self.fleet
        aps = f.autopilots
        pct = f.bat.pct[ks]
        capacity = np.array([aps[k].params["BAT_CAPACITY"] for k in ks.tolist()], dtype=float)
        state = np.where(f.bat.charge_rate_pct_s[ks] > 0.0, 7,
                         _CHARGE_STATE[f.bat.level[ks].astype(np.intp)])
        cells = np.full((len(ks), 10), 65535, dtype=np.int64)
        cells[:, 0] = np.minimum(self._voltage_mv(ks), 65534)
        remaining_s = _trunc(pct / 100.0 * f.bat.hover_endurance_s[ks])
        return (0, 1, 1, 32767, cells, -1, _trunc((100.0 - pct) / 100.0 * capacity), -1,
                _trunc(pct), remaining_s, state)

    def _extended_sys_state(self, ks: np.ndarray) -> Sequence[object]:
        aps = self.fleet.autopilots
        return (0, [aps[k].landed_state.value for k in ks.tolist()])

    def _global_position_int(self, ks: np.ndarray) -> Sequence[object]:
        dyn = self.fleet.dyn
        p = dyn.position_m[ks]
        lat, lon, alt = self._geo(p[:, 0], p[:, 1], p[:, 2])
        v = dyn.velocity_m_s[ks]
        hdg = _rint(dyn.yaw_deg[ks] * 100.0) % 36000
        aps = self.fleet.autopilots
        home_z = np.array([aps[k].state.home_m[2] for k in ks.tolist()], dtype=float)
        rel_mm = _rint((p[:, 2] - home_z) * 1000.0)
        return (self._time_boot_ms(), lat, lon, alt, rel_mm, _rint(v[:, 1] * 100.0),
                _rint(v[:, 0] * 100.0), _rint(-v[:, 2] * 100.0), hdg)

    def _local_position_ned(self, ks: np.ndarray) -> Sequence[object]:
        dyn = self.fleet.dyn
        p = dyn.position_m[ks] - self.fleet.local_origin_m[ks]
        v = dyn.velocity_m_s[ks]
        return (self._time_boot_ms(), p[:, 1], p[:, 0], -p[:, 2], v[:, 1], v[:, 0], -v[:, 2])

    def _attitude(self, ks: np.ndarray) -> Sequence[object]:
        dyn = self.fleet.dyn
        yaw_deg = dyn.yaw_deg[ks]
        cos, sin, wrapped = self._heading_trig(ks, yaw_deg)
        a = dyn.accel_m_s2[ks]
        a_north, a_east = a[:, 1], a[:, 0]
        forward = a_north * cos + a_east * sin
        right = -a_north * sin + a_east * cos
        g = msgs.GRAVITY_M_S2
        # atan2(+-0, g) is +-0: only a vehicle that accelerates needs math.atan2
        pitch = -forward
        roll = right.copy()
        tilted = np.flatnonzero(forward).tolist()
        if tilted:
            pitch[tilted] = [-math.atan2(x, g) for x in forward[tilted].tolist()]
        tilted = np.flatnonzero(right).tolist()
        if tilted:
            roll[tilted] = [math.atan2(x, g) for x in right[tilted].tolist()]
        return (self._time_boot_ms(), roll, pitch, wrapped, 0.0, 0.0, 0.0)

    def _heading_trig(self, ks: np.ndarray, yaw_deg: np.ndarray):
        """cos, sin and atan2(sin, cos) of the vehicles' headings (radians), as Python's math
        computes them, worked out again only for a vehicle whose heading changed."""
        cache = self._trig
        if cache is None or len(cache[0]) != self.fleet.n:
            n = self.fleet.n
            cache = self._trig = (np.zeros(n, dtype=bool), np.empty(n, dtype=np.int64),
                                  np.empty(n), np.empty(n), np.empty(n))
        known, last_bits, cos_all, sin_all, wrapped_all = cache
        bits = yaw_deg.view(np.int64)  # the very same float, -0.0 and NaN included
        changed = ks[~known[ks] | (last_bits[ks] != bits)]
        if len(changed):
            yaw = self.fleet.dyn.yaw_deg[changed]
            radians = (yaw * _DEG_TO_RAD).tolist()
            cos = [math.cos(y) for y in radians]
            sin = [math.sin(y) for y in radians]
            cos_all[changed] = cos
            sin_all[changed] = sin
            wrapped_all[changed] = [math.atan2(s, c) for s, c in zip(sin, cos, strict=True)]
            last_bits[changed] = yaw.view(np.int64)
            known[changed] = True
        return cos_all[ks], sin_all[ks], wrapped_all[ks]

    def _ground_speed(self, v: np.ndarray) -> np.ndarray:
        return np.array([math.hypot(e, n) for e, n in v[:, :2].tolist()], dtype=float)

    def _gps_raw_int(self, ks: np.ndarray) -> Sequence[object]:
        dyn = self.fleet.dyn
        p = dyn.position_m[ks]
        lat, lon, alt = self._geo(p[:, 0], p[:, 1], p[:, 2])
        v = dyn.velocity_m_s[ks]
        ground = self._ground_speed(v)
        course = np.array([math.atan2(e, n) * _RAD_TO_DEG for e, n in v[:, :2].tolist()],
                          dtype=float)
        cog = np.where(ground > 0.1, _rint(course * 100.0) % 36000, 0)
        time_usec = self._time_boot_ms() * 1000
        return (time_usec, 3, lat, lon, alt, 80, 120, _rint(ground * 100.0), cog, 14,
                alt, 500, 800, 100, 0, 0)

    def _vfr_hud(self, ks: np.ndarray) -> Sequence[object]:
        f = self.fleet
        dyn = f.dyn
        v = dyn.velocity_m_s[ks]
        air = dyn.airspeed_m_s()[ks]
        throttle = np.where(f.airborne[ks], 50, np.where(f.armed[ks], 10, 0))
        alt = f.world.origin.altitude_amsl_m + dyn.position_m[ks, 2]
        return (air, self._ground_speed(v), _trunc(dyn.yaw_deg[ks]) % 360, throttle, alt,
                v[:, 2])

    def _home_position(self, ks: np.ndarray) -> Sequence[object]:
        home = self._homes(ks)
        lat, lon, alt = self._geo(home[:, 0], home[:, 1], home[:, 2])
        time_usec = self._time_boot_ms() * 1000
        return (lat, lon, alt, home[:, 1], home[:, 0], -home[:, 2], [1.0, 0.0, 0.0, 0.0],
                0.0, 0.0, 0.0, time_usec)

    def _mission_current(self, ks: np.ndarray) -> Sequence[object]:
        aps = self.fleet.autopilots
        runners = [aps[k].mission for k in ks.tolist()]
        modes = [aps[k].mode is FlightMode.MISSION for k in ks.tolist()]
        return ([m.current for m in runners], [m.total for m in runners],
                [m.state for m in runners], modes)
