"""Builders of the MAVLink messages a vehicle sends, from its autopilot's state."""

from __future__ import annotations

import math

from emulator.flight.autopilot import Autopilot
from emulator.flight.battery import (
    BATTERY_CRITICAL,
    BATTERY_EMERGENCY,
    BATTERY_LOW,
    cell_voltage_v,
)
from emulator.flight.modes import FlightMode
from emulator.mavlink.codec import mavlink
from mavlink_vocabulary import (
    GpsFixType,
    MavAutopilot,
    MavBatteryChargeState,
    MavBatteryFunction,
    MavBatteryType,
    MavModeFlag,
    MavProtocolCapability,
    MavState,
    MavSysStatusSensor,
    MavType,
    MavVtolState,
)

__all__ = [
    "MAV_AUTOPILOT_INVALID",
    "MAV_AUTOPILOT_PX4",
    "MAV_TYPE_QUADROTOR",
    "MODE_FLAG_ARMED",
    "MODE_FLAG_AUTO",
    "MODE_FLAG_CUSTOM",
    "MODE_FLAG_GUIDED",
    "MODE_FLAG_STABILIZE",
    "PREARM_CHECK",
    "SENSORS",
    "STATE_ACTIVE",
    "STATE_CRITICAL",
    "STATE_EMERGENCY",
    "STATE_STANDBY",
    "attitude",
    "autopilot_version",
    "battery_status",
    "component_heartbeat",
    "extended_sys_state",
    "global_position_int",
    "gps_raw_int",
    "heartbeat",
    "home_position",
    "local_position_ned",
    "mission_current",
    "statustext",
    "sys_status",
    "vfr_hud",
]

# Plain ints named by the vocabulary: the batched telemetry (emulator.mavlink.telemetry) puts
# them into numpy arrays.
MAV_TYPE_QUADROTOR = int(MavType.QUADROTOR)
MAV_AUTOPILOT_PX4 = int(MavAutopilot.PX4)
MAV_AUTOPILOT_INVALID = int(MavAutopilot.INVALID)
GRAVITY_M_S2 = 9.80665

MODE_FLAG_CUSTOM = int(MavModeFlag.CUSTOM_MODE_ENABLED)
MODE_FLAG_AUTO = int(MavModeFlag.AUTO_ENABLED)
MODE_FLAG_GUIDED = int(MavModeFlag.GUIDED_ENABLED)
MODE_FLAG_STABILIZE = int(MavModeFlag.STABILIZE_ENABLED)
MODE_FLAG_ARMED = int(MavModeFlag.SAFETY_ARMED)
STATE_STANDBY, STATE_ACTIVE = int(MavState.STANDBY), int(MavState.ACTIVE)
STATE_CRITICAL, STATE_EMERGENCY = int(MavState.CRITICAL), int(MavState.EMERGENCY)
INT16_MAX = 32767  # BATTERY_STATUS.temperature: unknown
MAVLINK_VERSION = 3  # HEARTBEAT.mavlink_version as PX4 sends it

_S = MavSysStatusSensor
SENSORS = int(
    _S.SENSOR_3D_GYRO | _S.SENSOR_3D_ACCEL | _S.SENSOR_3D_MAG | _S.SENSOR_ABSOLUTE_PRESSURE
    | _S.SENSOR_GPS | _S.SENSOR_ANGULAR_RATE_CONTROL | _S.SENSOR_ATTITUDE_STABILIZATION
    | _S.SENSOR_YAW_POSITION | _S.SENSOR_Z_ALTITUDE_CONTROL | _S.SENSOR_XY_POSITION_CONTROL
    | _S.SENSOR_MOTOR_OUTPUTS | _S.GEOFENCE | _S.AHRS | _S.SENSOR_BATTERY
)
PREARM_CHECK = int(_S.PREARM_CHECK)

_C = MavProtocolCapability
CAPABILITIES = int(
    _C.MISSION_FLOAT | _C.PARAM_FLOAT | _C.MISSION_INT | _C.COMMAND_INT
    | _C.PARAM_ENCODE_BYTEWISE | _C.SET_POSITION_TARGET_LOCAL_NED
    | _C.SET_POSITION_TARGET_GLOBAL_INT | _C.MAVLINK2
)
FLIGHT_SW_VERSION = (1 << 24) | (15 << 16) | (0 << 8) | 0xFF  # 1.15.0 release


def _e7(deg: float) -> int:
    return round(deg * 1e7)


def _geo(ap: Autopilot, p: tuple[float, float, float]) -> tuple[int, int, int]:
    lat, lon, alt = ap.fleet.world.origin.to_geodetic(*p)
    return _e7(lat), _e7(lon), round(alt * 1000.0)


def component_heartbeat(ap: Autopilot, mav_type: int) -> mavlink.MAVLink_message:
    """The heartbeat of one of the vehicle's other components (camera, gimbal). Its base and
    custom mode are the vehicle's mode: MAVSDK's follow_me plugin reads every heartbeat of
    the system, and one without the follow-target mode would make it stop following."""
    return mavlink.MAVLink_heartbeat_message(mav_type, MAV_AUTOPILOT_INVALID, MODE_FLAG_CUSTOM,
                                             ap.mode.custom_mode, STATE_ACTIVE, MAVLINK_VERSION)


def heartbeat(ap: Autopilot) -> mavlink.MAVLink_message:
    mode = ap.mode
    base = MODE_FLAG_CUSTOM | MODE_FLAG_STABILIZE | MODE_FLAG_GUIDED
    if mode is not FlightMode.OFFBOARD:
        base |= MODE_FLAG_AUTO
    if ap.armed:
        base |= MODE_FLAG_ARMED
    level = int(ap.fleet.bat.level[ap.k])
    if level == BATTERY_EMERGENCY:
        state = STATE_EMERGENCY
    elif level == BATTERY_CRITICAL:
        state = STATE_CRITICAL
    else:
        state = STATE_ACTIVE if ap.armed else STATE_STANDBY
    return mavlink.MAVLink_heartbeat_message(
        MAV_TYPE_QUADROTOR, MAV_AUTOPILOT_PX4, base, mode.custom_mode, state, MAVLINK_VERSION
    )


def _voltage_mv(ap: Autopilot) -> int:
    p = ap.params
    cell = cell_voltage_v(ap.battery_pct, p["BAT_V_EMPTY"], p["BAT_V_CHARGED"])
    return int(cell * p["BAT_N_CELLS"] * 1000.0)


def sys_status(ap: Autopilot) -> mavlink.MAVLink_message:
    health = SENSORS
    if ap.fleet.bat.level[ap.k] < BATTERY_CRITICAL:
        health |= PREARM_CHECK
    present = SENSORS | PREARM_CHECK
    return mavlink.MAVLink_sys_status_message(
        present, present, health, 150, _voltage_mv(ap), -1, int(ap.battery_pct), 0, 0, 0, 0, 0, 0
    )


_CHARGE_STATE = {0: MavBatteryChargeState.OK, BATTERY_LOW: MavBatteryChargeState.LOW,
                 BATTERY_CRITICAL: MavBatteryChargeState.CRITICAL,
                 BATTERY_EMERGENCY: MavBatteryChargeState.EMERGENCY}


def battery_status(ap: Autopilot) -> mavlink.MAVLink_message:
    f, k = ap.fleet, ap.k
    pct = ap.battery_pct
    capacity = ap.params["BAT_CAPACITY"]
    charging = f.bat.charge_rate_pct_s[k] > 0.0
    state = MavBatteryChargeState.CHARGING if charging else _CHARGE_STATE[int(f.bat.level[k])]
    cells = [65535] * 10
    cells[0] = min(_voltage_mv(ap), 65534)
    remaining_s = int(pct / 100.0 * f.bat.hover_endurance_s[k])
    return mavlink.MAVLink_battery_status_message(
        0, MavBatteryFunction.ALL, MavBatteryType.LIPO, INT16_MAX, cells, -1,
        int((100.0 - pct) / 100.0 * capacity), -1, int(pct), remaining_s, state,
    )


def extended_sys_state(ap: Autopilot) -> mavlink.MAVLink_message:
    return mavlink.MAVLink_extended_sys_state_message(MavVtolState.UNDEFINED, ap.landed_state.value)


def global_position_int(ap: Autopilot, time_boot_ms: int) -> mavlink.MAVLink_message:
    f, k = ap.fleet, ap.k
    p = ap.position_m
    lat, lon, alt = _geo(ap, p)
    v = f.dyn.velocity_m_s[k]
    hdg = round(f.dyn.yaw_deg[k] * 100.0) % 36000
    rel_mm = round((p[2] - ap.home_m[2]) * 1000.0)
    return mavlink.MAVLink_global_position_int_message(
        time_boot_ms, lat, lon, alt, rel_mm,
        round(v[1] * 100.0), round(v[0] * 100.0), round(-v[2] * 100.0), hdg,
    )


def local_position_ned(ap: Autopilot, time_boot_ms: int) -> mavlink.MAVLink_message:
    x, y, z = (a - b for a, b in zip(ap.position_m, ap.fleet.local_origin(ap.k), strict=True))
    v = ap.fleet.dyn.velocity_m_s[ap.k]
    return mavlink.MAVLink_local_position_ned_message(
        time_boot_ms, y, x, -z, float(v[1]), float(v[0]), float(-v[2])
    )


def attitude(ap: Autopilot, time_boot_ms: int) -> mavlink.MAVLink_message:
    f, k = ap.fleet, ap.k
    yaw = math.radians(float(f.dyn.yaw_deg[k]))
    a = f.dyn.accel_m_s2[k]
    a_north, a_east = float(a[1]), float(a[0])
    forward = a_north * math.cos(yaw) + a_east * math.sin(yaw)
    right = -a_north * math.sin(yaw) + a_east * math.cos(yaw)
    pitch = -math.atan2(forward, GRAVITY_M_S2)
    roll = math.atan2(right, GRAVITY_M_S2)
    yaw_wrapped = math.atan2(math.sin(yaw), math.cos(yaw))
    return mavlink.MAVLink_attitude_message(time_boot_ms, roll, pitch, yaw_wrapped, 0.0, 0.0, 0.0)


def gps_raw_int(ap: Autopilot, time_usec: int) -> mavlink.MAVLink_message:
    f, k = ap.fleet, ap.k
    lat, lon, alt = _geo(ap, ap.position_m)
    v = f.dyn.velocity_m_s[k]
    ground = math.hypot(float(v[0]), float(v[1]))
    cog = round(math.degrees(math.atan2(v[0], v[1])) * 100.0) % 36000 if ground > 0.1 else 0
    fix, satellites = (GpsFixType.NO_GPS, 0) if ap.failures.gps_off else (GpsFixType.FIX_3D, 14)
    return mavlink.MAVLink_gps_raw_int_message(
        time_usec, fix, lat, lon, alt, 80, 120, round(ground * 100.0), cog, satellites,
        alt, 500, 800, 100, 0, 0,
    )


def vfr_hud(ap: Autopilot) -> mavlink.MAVLink_message:
    f, k = ap.fleet, ap.k
    v = f.dyn.velocity_m_s[k]
    air = f.dyn.airspeed_m_s()[k]
    ground = math.hypot(float(v[0]), float(v[1]))
    throttle = 50 if ap.in_air else (10 if ap.armed else 0)
    alt = ap.fleet.world.origin.altitude_amsl_m + ap.position_m[2]
    return mavlink.MAVLink_vfr_hud_message(
        float(air), ground, int(f.dyn.yaw_deg[k]) % 360, throttle, alt, float(v[2])
    )


def home_position(ap: Autopilot, time_usec: int) -> mavlink.MAVLink_message:
    lat, lon, alt = _geo(ap, ap.home_m)
    hx, hy, hz = ap.home_m
    return mavlink.MAVLink_home_position_message(
        lat, lon, alt, hy, hx, -hz, [1.0, 0.0, 0.0, 0.0], 0.0, 0.0, 0.0, time_usec
    )


def mission_current(ap: Autopilot) -> mavlink.MAVLink_message:
    m = ap.mission
    return mavlink.MAVLink_mission_current_message(
        m.current, m.total, m.state, 1 if ap.mode is FlightMode.MISSION else 0
    )


def autopilot_version(ap: Autopilot) -> mavlink.MAVLink_message:
    return mavlink.MAVLink_autopilot_version_message(
        CAPABILITIES, FLIGHT_SW_VERSION, 0, 0, 0, [0] * 8, [0] * 8, [0] * 8, 0x26AC, 0x0011,
        0x4D53570000000000 + ap.k + 1,
    )


def statustext(severity: int, text: str) -> mavlink.MAVLink_message:
    return mavlink.MAVLink_statustext_message(severity, text.encode("ascii", "replace")[:50])
