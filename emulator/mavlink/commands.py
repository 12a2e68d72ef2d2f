"""The command protocol: COMMAND_LONG / COMMAND_INT -> autopilot calls -> a `Reply`.

Each handler takes the vehicle and the normalised command, validates the parameters (NaN
means 'unset' where PX4 says so), calls the autopilot, and returns a `Reply`: a MAV_RESULT,
an optional reason that becomes a STATUSTEXT, and what follows an accepted ACK. Handlers are
found by their `MavCmd` member.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from emulator.flight.mission import FRAMES_AMSL, FRAMES_RELATIVE
from emulator.flight.modes import decode_px4_mode
from emulator.flight.refusal import CommandRefused
from emulator.mavlink.calibration import preflight_calibration
from emulator.mavlink.command_args import CommandArgs
from emulator.mavlink.reply import Action, Reply, SendOnce
from emulator.mavlink.vehicle import Vehicle
from mavlink_vocabulary import (
    FailureType,
    FailureUnit,
    MavCmd,
    MavFrame,
    MavModeFlag,
    MavResult,
    MessageId,
)

__all__ = ["FAILURE_UNITS", "HANDLERS", "CommandArgs", "Reply", "execute_command"]

FORCE_DISARM_MAGIC = 21196.0  # MAV_CMD_COMPONENT_ARM_DISARM param2: disarm even in flight


def _finite(value: float) -> bool:
    return math.isfinite(value)


def _local_target(v: Vehicle, a: CommandArgs, what: str) -> tuple[float, float, float]:
    """Where a command's lat/lon/alt point is, in local metres (unset parts: current)."""
    ap = v.ap
    origin = ap.fleet.world.origin
    x, y, z = ap.position_m
    if a.latitude_deg is not None and a.longitude_deg is not None:
        if not (-90.0 <= a.latitude_deg <= 90.0 and -180.0 <= a.longitude_deg <= 180.0):
            raise CommandRefused(f"{what} refused: latitude/longitude out of range")
        x, y, _ = origin.to_local(a.latitude_deg, a.longitude_deg, origin.altitude_amsl_m)
    if math.isinf(a.altitude_m):
        raise CommandRefused(f"{what} refused: altitude is infinite")
    if _finite(a.altitude_m):
        if a.frame in FRAMES_RELATIVE:
            z = ap.home_m[2] + a.altitude_m
        elif a.frame in FRAMES_AMSL:
            z = a.altitude_m - origin.altitude_amsl_m
        else:
            raise CommandRefused(f"{what} refused: frame {a.frame} unsupported")
    return x, y, z


def _arm(v: Vehicle, a: CommandArgs) -> Reply:
    if a.p1 == 1.0:
        v.ap.arm()
    elif a.p1 == 0.0:
        v.ap.disarm(force=a.p2 == FORCE_DISARM_MAGIC)
    else:
        return Reply.denied("Arm/disarm: param1 must be 0 or 1")
    return Reply.accepted()


def _takeoff(v: Vehicle, a: CommandArgs) -> Reply:
    ap = v.ap
    altitude = None
    if _finite(a.altitude_m):
        home_amsl = ap.fleet.world.origin.altitude_amsl_m + ap.home_m[2]
        if a.altitude_m <= home_amsl:
            return Reply.denied(
                f"Takeoff: {a.altitude_m:.1f} m AMSL is below home ({home_amsl:.1f} m AMSL)")
        altitude = a.altitude_m - home_amsl
    elif math.isinf(a.altitude_m):
        return Reply.denied("Takeoff: altitude is infinite")
    ap.takeoff(altitude)
    return Reply.accepted()


def _land(v: Vehicle, a: CommandArgs) -> Reply:
    at = None
    if a.latitude_deg is not None:
        x, y, _ = _local_target(v, a, "Land")
        at = (x, y)
    v.ap.land(at)
    return Reply.accepted()


def _rtl(v: Vehicle, a: CommandArgs) -> Reply:
    v.ap.return_to_launch()
    return Reply.accepted()


def _set_mode(v: Vehicle, a: CommandArgs) -> Reply:
    if not (_finite(a.p1) and _finite(a.p2)):
        return Reply.denied("Set mode: mode parameters must be numbers")
    if not int(a.p1) & MavModeFlag.CUSTOM_MODE_ENABLED:  # DO_SET_MODE's param1: base mode
        return Reply.denied("Set mode: only PX4 custom modes are supported")
    sub = int(a.p3) if _finite(a.p3) else 0
    mode = decode_px4_mode(int(a.p2), sub)
    if mode is None:
        return Reply.denied(f"Set mode: unknown PX4 mode {int(a.p2)}/{sub}")
    v.ap.set_mode(mode, wall_now_s=v.wall_now_s)
    return Reply.accepted()


def _reposition(v: Vehicle, a: CommandArgs) -> Reply:
    target = _local_target(v, a, "Reposition")
    speed = a.p1 if a.p1 > 0 else None  # NaN, 0 or negative: the configured speed
    yaw = math.degrees(a.p4) % 360.0 if _finite(a.p4) else math.nan
    v.ap.reposition(target, speed_m_s=speed, yaw_deg=yaw)
    return Reply.accepted()


def _orbit(v: Vehicle, a: CommandArgs) -> Reply:
    """MAV_CMD_DO_ORBIT: p1 radius (m, positive clockwise), p2 speed (m/s), p3 yaw behaviour,
    x/y/z the centre, z AMSL (unset: the current centre, or where the vehicle is)."""
    ap = v.ap
    center: list[float | None] = [None, None, None]
    if a.latitude_deg is not None or _finite(a.altitude_m):
        # PX4 reads the centre's altitude as AMSL whatever the frame (MAVSDK's do_orbit sends
        # an absolute altitude in a COMMAND_INT of frame GLOBAL_RELATIVE_ALT)
        amsl = CommandArgs(a.command, a.p1, a.p2, a.p3, a.p4, a.latitude_deg, a.longitude_deg,
                           a.altitude_m, MavFrame.GLOBAL)
        x, y, z = _local_target(v, amsl, "Orbit")
        if a.latitude_deg is not None:
            center[:2] = [x, y]
        if _finite(a.altitude_m):
            center[2] = z
    ap.orbit.start((center[0], center[1], center[2]), a.p1, a.p2, a.p3)
    return Reply.accepted()


def _set_home(v: Vehicle, a: CommandArgs) -> Reply:
    ap = v.ap
    if a.p1 == 1.0:
        x, y, _ = ap.position_m
        ground_z = 0.0 if ap.in_air else ap.position_m[2]
        ap.set_home((x, y, ground_z))
    else:
        if a.latitude_deg is None or not _finite(a.altitude_m):
            return Reply.denied("Set home: latitude, longitude and altitude required")
        frame = a.frame if a.frame in FRAMES_RELATIVE else MavFrame.GLOBAL
        args = CommandArgs(a.command, a.p1, a.p2, a.p3, a.p4, a.latitude_deg, a.longitude_deg,
                           a.altitude_m, frame)
        ap.set_home(_local_target(v, args, "Set home"))
    return Reply.accepted()


def _change_speed(v: Vehicle, a: CommandArgs) -> Reply:
    kind = a.p1 if _finite(a.p1) else 1.0
    v.ap.change_speed(kind, a.p2)
    return Reply.accepted()


def _yaw(v: Vehicle, a: CommandArgs) -> Reply:
    rate = a.p2 if _finite(a.p2) else 0.0
    direction = -1 if _finite(a.p3) and a.p3 < 0 else 1
    v.ap.set_yaw(a.p1, rate_deg_s=rate, relative=a.p4 == 1.0, direction=direction)
    return Reply.accepted()


def _mission_start(v: Vehicle, a: CommandArgs) -> Reply:
    first = int(a.p1) if _finite(a.p1) and a.p1 > 0 else None
    v.ap.mission.enter_mission_mode(first)
    return Reply.accepted()


def _set_mission_current(v: Vehicle, a: CommandArgs) -> Reply:
    if not _finite(a.p1) or a.p1 < 0:
        return Reply.denied("Set mission item: index must be >= 0")
    v.ap.mission.set_current(int(a.p1))
    return Reply.accepted()


def _message_interval(v: Vehicle, a: CommandArgs) -> Reply:
    if not (_finite(a.p1) and _finite(a.p2)):
        return Reply.denied("Message interval: parameters must be numbers")
    interval_us = a.p2
    if a.p1 < 0:
        return Reply.denied(f"Message interval: message id {a.p1:g} is invalid")
    if interval_us < -1:
        return Reply.denied(f"Message interval: {interval_us:g} us is invalid")
    interval = None if interval_us == 0 else math.inf if interval_us == -1 else interval_us / 1e6
    if not v.set_stream_interval(int(a.p1), interval):
        return Reply.denied(f"Message interval: message {int(a.p1)} rate cannot be set")
    return Reply.accepted()


def _request_message(v: Vehicle, a: CommandArgs) -> Reply:
    if not _finite(a.p1) or not v.can_send_once(int(a.p1)):
        return Reply.denied()
    return Reply.accepted(SendOnce(int(a.p1)))


def _autopilot_capabilities(v: Vehicle, a: CommandArgs) -> Reply:
    return Reply.accepted(SendOnce(MessageId.AUTOPILOT_VERSION))


def _get_home(v: Vehicle, a: CommandArgs) -> Reply:
    return Reply.accepted(SendOnce(MessageId.HOME_POSITION))


def _gimbal(v: Vehicle, a: CommandArgs) -> Reply:
    if v.gimbal is None:
        return Reply(MavResult.UNSUPPORTED)  # no gimbal on this vehicle
    return v.gimbal.handle_command(v.ap, a, v.command_peer)


def _camera(v: Vehicle, a: CommandArgs) -> Reply:
    return v.camera.handle_command(v.ap, a, v.wall_now_s)


# MAV_CMD_INJECT_FAILURE: FAILURE_UNIT -> what emulator.flight.failures models
FAILURE_UNITS = {
    FailureUnit.SENSOR_GPS: "gps",
    FailureUnit.SYSTEM_BATTERY: "battery",
    FailureUnit.SYSTEM_MOTOR: "motor",
    FailureUnit.SYSTEM_MAVLINK_SIGNAL: "mavlink",
}
_RESTORABLE = frozenset({"gps", "mavlink"})


def _inject_failure(v: Vehicle, a: CommandArgs) -> Reply:
    ap = v.ap
    if ap.params["SYS_FAILURE_EN"] != 1.0:
        return Reply.denied("Failure injection disabled: set SYS_FAILURE_EN to 1")
    unit_id = int(a.p1) if _finite(a.p1) else -1
    unit = FAILURE_UNITS[FailureUnit(unit_id)] if unit_id in FAILURE_UNITS else None
    kind = int(a.p2) if _finite(a.p2) else -1
    if unit is None or kind not in (FailureType.OK, FailureType.OFF) or (
            kind == FailureType.OK and unit not in _RESTORABLE):
        return Reply(MavResult.UNSUPPORTED)
    if kind == FailureType.OK:
        ap.failures.restore(unit, "injection")
        return Reply.accepted()
    failed_unit = unit

    def fail() -> None:  # after the ACK: a vehicle whose MAVLink goes off still answers this
        ap.failures.fail(failed_unit, "injection")
        if failed_unit == "mavlink" and v.on_mavlink_signal is not None:
            v.on_mavlink_signal(ap)
    return Reply.accepted(Action(fail))


Handler = Callable[[Vehicle, CommandArgs], Reply]
HANDLERS: dict[MavCmd, Handler] = {
    MavCmd.COMPONENT_ARM_DISARM: _arm,
    MavCmd.NAV_TAKEOFF: _takeoff,
    MavCmd.NAV_LAND: _land,
    MavCmd.NAV_RETURN_TO_LAUNCH: _rtl,
    MavCmd.DO_SET_MODE: _set_mode,
    MavCmd.DO_REPOSITION: _reposition,
    MavCmd.DO_ORBIT: _orbit,
    MavCmd.PREFLIGHT_CALIBRATION: preflight_calibration,
    MavCmd.DO_SET_HOME: _set_home,
    MavCmd.DO_CHANGE_SPEED: _change_speed,
    MavCmd.CONDITION_YAW: _yaw,
    MavCmd.MISSION_START: _mission_start,
    MavCmd.DO_SET_MISSION_CURRENT: _set_mission_current,
    MavCmd.SET_MESSAGE_INTERVAL: _message_interval,
    MavCmd.REQUEST_MESSAGE: _request_message,
    MavCmd.REQUEST_AUTOPILOT_CAPABILITIES: _autopilot_capabilities,
    MavCmd.GET_HOME_POSITION: _get_home,
    MavCmd.INJECT_FAILURE: _inject_failure,
    MavCmd.IMAGE_START_CAPTURE: _camera,
    MavCmd.IMAGE_STOP_CAPTURE: _camera,
    MavCmd.REQUEST_CAMERA_INFORMATION: _camera,
    MavCmd.REQUEST_CAMERA_SETTINGS: _camera,
    MavCmd.REQUEST_STORAGE_INFORMATION: _camera,
    MavCmd.REQUEST_CAMERA_CAPTURE_STATUS: _camera,
    MavCmd.SET_CAMERA_MODE: _camera,
    MavCmd.DO_GIMBAL_MANAGER_PITCHYAW: _gimbal,
    MavCmd.DO_GIMBAL_MANAGER_CONFIGURE: _gimbal,
    MavCmd.VIDEO_START_CAPTURE: _camera,
    MavCmd.VIDEO_STOP_CAPTURE: _camera,
    MavCmd.VIDEO_START_STREAMING: _camera,
    MavCmd.VIDEO_STOP_STREAMING: _camera,
    MavCmd.REQUEST_VIDEO_STREAM_INFORMATION: _camera,
    MavCmd.REQUEST_VIDEO_STREAM_STATUS: _camera,
}


def execute_command(v: Vehicle, args: CommandArgs) -> Reply:
    """Carry out one command on vehicle `v`: its reply (UNSUPPORTED for an unknown one)."""
    if args.command not in HANDLERS:
        return Reply(MavResult.UNSUPPORTED)
    try:
        return HANDLERS[MavCmd(args.command)](v, args)
    except CommandRefused as refusal:
        return Reply.denied(str(refusal))
