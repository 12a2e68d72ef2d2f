"""The command protocol: COMMAND_LONG / COMMAND_INT -> autopilot calls -> COMMAND_ACK.

Each handler validates its parameters (NaN means 'unset' where PX4 says so), calls the
autopilot, and returns a MAV_RESULT with an optional reason that becomes a STATUSTEXT.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from emulator.flight.modes import decode_px4_mode
from emulator.flight.refusal import CommandRefused

if TYPE_CHECKING:
    from emulator.mavlink.vehicle_link import VehicleLink

__all__ = ["CommandArgs", "Result", "execute_command"]

INT32_MAX = 2**31 - 1
FRAMES_AMSL = frozenset({0, 5})
FRAMES_RELATIVE = frozenset({3, 6})


class Result:
    """MAV_RESULT values."""

    ACCEPTED = 0
    TEMPORARILY_REJECTED = 1
    DENIED = 2
    UNSUPPORTED = 3
    FAILED = 4


@dataclass(frozen=True, slots=True)
class CommandArgs:
    """One command, normalised: lat/lon in degrees (None when unset)."""

    command: int
    p1: float
    p2: float
    p3: float
    p4: float
    latitude_deg: float | None
    longitude_deg: float | None
    altitude_m: float
    frame: int  # altitude frame: AMSL (0/5) or relative to home (3/6)

    @classmethod
    def from_long(cls, m) -> CommandArgs:
        lat = m.param5 if math.isfinite(m.param5) else None
        lon = m.param6 if math.isfinite(m.param6) else None
        return cls(m.command, m.param1, m.param2, m.param3, m.param4, lat, lon, m.param7, 0)

    @classmethod
    def from_int(cls, m) -> CommandArgs:
        lat = None if m.x in (INT32_MAX, 0) and m.y in (INT32_MAX, 0) else m.x * 1e-7
        lon = None if lat is None else m.y * 1e-7
        return cls(m.command, m.param1, m.param2, m.param3, m.param4, lat, lon, m.z, m.frame)


Outcome = tuple[int, str | None]


def _finite(value: float) -> bool:
    return math.isfinite(value)


def _local_target(link: VehicleLink, a: CommandArgs, what: str) -> tuple[float, float, float]:
    """Where a command's lat/lon/alt point is, in local metres (unset parts: current)."""
    ap = link.ap
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


def _arm(link: VehicleLink, a: CommandArgs) -> Outcome:
    if a.p1 == 1.0:
        link.ap.arm()
    elif a.p1 == 0.0:
        link.ap.disarm(force=a.p2 == 21196.0)
    else:
        return Result.DENIED, "Arm/disarm: param1 must be 0 or 1"
    return Result.ACCEPTED, None


def _takeoff(link: VehicleLink, a: CommandArgs) -> Outcome:
    ap = link.ap
    altitude = None
    if _finite(a.altitude_m):
        home_amsl = ap.fleet.world.origin.altitude_amsl_m + ap.home_m[2]
        if a.altitude_m <= home_amsl:
            return Result.DENIED, (
                f"Takeoff: {a.altitude_m:.1f} m AMSL is below home ({home_amsl:.1f} m AMSL)"
            )
        altitude = a.altitude_m - home_amsl
    elif math.isinf(a.altitude_m):
        return Result.DENIED, "Takeoff: altitude is infinite"
    ap.takeoff(altitude)
    return Result.ACCEPTED, None


def _land(link: VehicleLink, a: CommandArgs) -> Outcome:
    at = None
    if a.latitude_deg is not None:
        x, y, _ = _local_target(link, a, "Land")
        at = (x, y)
    link.ap.land(at)
    return Result.ACCEPTED, None


def _rtl(link: VehicleLink, a: CommandArgs) -> Outcome:
    link.ap.return_to_launch()
    return Result.ACCEPTED, None


def _set_mode(link: VehicleLink, a: CommandArgs) -> Outcome:
    if not (_finite(a.p1) and _finite(a.p2)):
        return Result.DENIED, "Set mode: mode parameters must be numbers"
    if not int(a.p1) & 1:
        return Result.DENIED, "Set mode: only PX4 custom modes are supported"
    sub = int(a.p3) if _finite(a.p3) else 0
    mode = decode_px4_mode(int(a.p2), sub)
    if mode is None:
        return Result.DENIED, f"Set mode: unknown PX4 mode {int(a.p2)}/{sub}"
    link.ap.set_mode(mode, wall_now_s=link.wall_now_s)
    return Result.ACCEPTED, None


def _reposition(link: VehicleLink, a: CommandArgs) -> Outcome:
    target = _local_target(link, a, "Reposition")
    speed = a.p1 if a.p1 > 0 else None  # NaN, 0 or negative: the configured speed
    yaw = math.degrees(a.p4) % 360.0 if _finite(a.p4) else math.nan
    link.ap.reposition(target, speed_m_s=speed, yaw_deg=yaw)
    return Result.ACCEPTED, None


def _set_home(link: VehicleLink, a: CommandArgs) -> Outcome:
    ap = link.ap
    if a.p1 == 1.0:
        x, y, _ = ap.position_m
        ground_z = 0.0 if ap.in_air else ap.position_m[2]
        ap.set_home((x, y, ground_z))
    else:
        if a.latitude_deg is None or not _finite(a.altitude_m):
            return Result.DENIED, "Set home: latitude, longitude and altitude required"
        frame = a.frame if a.frame in FRAMES_RELATIVE else 0
        args = CommandArgs(a.command, a.p1, a.p2, a.p3, a.p4, a.latitude_deg, a.longitude_deg,
                           a.altitude_m, frame)
        ap.set_home(_local_target(link, args, "Set home"))
    return Result.ACCEPTED, None


def _change_speed(link: VehicleLink, a: CommandArgs) -> Outcome:
    kind = a.p1 if _finite(a.p1) else 1.0
    link.ap.change_speed(kind, a.p2)
    return Result.ACCEPTED, None


def _yaw(link: VehicleLink, a: CommandArgs) -> Outcome:
    rate = a.p2 if _finite(a.p2) else 0.0
    direction = -1 if _finite(a.p3) and a.p3 < 0 else 1
    link.ap.set_yaw(a.p1, rate_deg_s=rate, relative=a.p4 == 1.0, direction=direction)
    return Result.ACCEPTED, None


def _mission_start(link: VehicleLink, a: CommandArgs) -> Outcome:
    first = int(a.p1) if _finite(a.p1) and a.p1 > 0 else None
    link.ap.mission.enter_mission_mode(first)
    return Result.ACCEPTED, None


def _set_mission_current(link: VehicleLink, a: CommandArgs) -> Outcome:
    if not _finite(a.p1) or a.p1 < 0:
        return Result.DENIED, "Set mission item: index must be >= 0"
    link.ap.mission.set_current(int(a.p1))
    return Result.ACCEPTED, None


def _message_interval(link: VehicleLink, a: CommandArgs) -> Outcome:
    if not (_finite(a.p1) and _finite(a.p2)):
        return Result.DENIED, "Message interval: parameters must be numbers"
    interval_us = a.p2
    if a.p1 < 0:
        return Result.DENIED, f"Message interval: message id {a.p1:g} is invalid"
    if interval_us < -1:
        return Result.DENIED, f"Message interval: {interval_us:g} us is invalid"
    interval = None if interval_us == 0 else math.inf if interval_us == -1 else interval_us / 1e6
    if not link.set_stream_interval(int(a.p1), interval):
        return Result.DENIED, f"Message interval: message {int(a.p1)} rate cannot be set"
    return Result.ACCEPTED, None


def _request_message(link: VehicleLink, a: CommandArgs) -> Outcome:
    if not _finite(a.p1):
        return Result.DENIED, None
    if not link.can_send_once(int(a.p1)):
        return Result.DENIED, None
    link.after_ack(lambda: link.send_once(int(a.p1)))
    return Result.ACCEPTED, None


def _autopilot_capabilities(link: VehicleLink, a: CommandArgs) -> Outcome:
    link.after_ack(lambda: link.send_once(148))
    return Result.ACCEPTED, None


def _get_home(link: VehicleLink, a: CommandArgs) -> Outcome:
    link.after_ack(lambda: link.send_once(242))
    return Result.ACCEPTED, None


def _camera(link: VehicleLink, a: CommandArgs) -> Outcome:
    return link.camera.handle_command(a)


# MAV_CMD_INJECT_FAILURE: FAILURE_UNIT -> what emulator.flight.failures models
FAILURE_UNITS = {4: "gps", 100: "battery", 101: "motor", 105: "mavlink"}
FAILURE_OK, FAILURE_OFF = 0, 1


def _inject_failure(link: VehicleLink, a: CommandArgs) -> Outcome:
    ap = link.ap
    if ap.params["SYS_FAILURE_EN"] != 1.0:
        return Result.DENIED, "Failure injection disabled: set SYS_FAILURE_EN to 1"
    unit = FAILURE_UNITS.get(int(a.p1)) if _finite(a.p1) else None
    kind = int(a.p2) if _finite(a.p2) else -1
    if unit is None or kind not in (FAILURE_OK, FAILURE_OFF) or (
            kind == FAILURE_OK and unit not in ("gps", "mavlink")):
        return Result.UNSUPPORTED, None
    if kind == FAILURE_OK:
        ap.failures.restore(unit, "injection")
        return Result.ACCEPTED, None

    def fail() -> None:  # after the ACK: a vehicle whose MAVLink goes off still answers this
        ap.failures.fail(unit, "injection")
        if unit == "mavlink" and link.on_mavlink_signal is not None:
            link.on_mavlink_signal(ap)
    link.after_ack(fail)
    return Result.ACCEPTED, None


HANDLERS: dict[int, Callable[[VehicleLink, CommandArgs], Outcome]] = {
    400: _arm,
    22: _takeoff,
    21: _land,
    20: _rtl,
    176: _set_mode,
    192: _reposition,
    179: _set_home,
    178: _change_speed,
    115: _yaw,
    300: _mission_start,
    224: _set_mission_current,
    511: _message_interval,
    512: _request_message,
    520: _autopilot_capabilities,
    410: _get_home,
    420: _inject_failure,
    2000: _camera,
    2001: _camera,
    521: _camera,
    522: _camera,
    525: _camera,
    527: _camera,
    530: _camera,
}


def execute_command(link: VehicleLink, args: CommandArgs) -> Outcome:
    handler = HANDLERS.get(args.command)
    if handler is None:
        return Result.UNSUPPORTED, None
    try:
        return handler(link, args)
    except CommandRefused as refusal:
        return Result.DENIED, str(refusal)
