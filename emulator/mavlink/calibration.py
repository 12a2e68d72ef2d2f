"""MAV_CMD_PREFLIGHT_CALIBRATION as PX4 answers it: the ACK, then the calibration's progress
as "[cal] ..." STATUSTEXTs (protocol version 2, the texts QGroundControl and MAVSDK's
calibration plugin read). The emulated sensors need no calibration, so each one completes
at once: gyro, level horizon and baro in one go; accelerometer and magnetometer after the
six orientations, each detected and done in turn (the vehicle "is turned" by itself).
Refused while armed, as PX4; a command with every parameter 0 cancels (nothing is running).
"""

from __future__ import annotations

import math

from emulator.flight.refusal import Severity
from emulator.mavlink import messages as msgs
from emulator.mavlink.command_args import CommandArgs
from emulator.mavlink.reply import Reply, SendMessage
from emulator.mavlink.vehicle import Vehicle
from emulator.truth_events import TruthEventKind
from mavlink_vocabulary import MavResult

__all__ = ["SIDES", "preflight_calibration"]

SIDES = ("down", "up", "left", "right", "front", "back")


def _text(text: str, severity: int = Severity.INFO) -> SendMessage:
    return SendMessage(msgs.statustext(severity, f"[cal] {text}"))


def _simple(name: str) -> list[SendMessage]:
    out = [_text(f"calibration started: 2 {name}")]
    out += [_text(f"progress <{pct}>") for pct in (0, 25, 50, 75, 100)]
    return [*out, _text(f"calibration done: {name}")]


def _six_sides(name: str) -> list[SendMessage]:
    out = [_text(f"calibration started: 2 {name}"), _text(f"pending: {' '.join(SIDES)}")]
    for i, side in enumerate(SIDES, start=1):
        out += [_text(f"{side} orientation detected"),
                _text(f"progress <{round(100 * i / len(SIDES))}>"),
                _text(f"{side} side done, rotate to a different side")]
    return [*out, _text(f"calibration done: {name}")]


def _is(value: float, *wanted: float) -> bool:
    return math.isfinite(value) and value in wanted


def preflight_calibration(v: Vehicle, a: CommandArgs) -> Reply:
    """p1 gyro, p2 magnetometer, p3 baro, p5 accelerometer (1) or level horizon (2)."""
    if all(p == 0.0 for p in (a.p1, a.p2, a.p3, a.p4, a.altitude_m)) and a.latitude_deg in (
            None, 0.0):
        return Reply.accepted(_text("calibration cancelled"))
    if v.ap.armed:
        return Reply(MavResult.TEMPORARILY_REJECTED, "[cal] calibration denied: system armed")
    accel = 0.0 if a.latitude_deg is None else a.latitude_deg  # param5 (COMMAND_LONG)
    if _is(a.p1, 1.0):
        sensor, steps = "gyro", _simple("gyro")
    elif _is(a.p2, 1.0):
        sensor, steps = "mag", _six_sides("mag")
    elif _is(a.p3, 1.0):
        sensor, steps = "baro", _simple("baro")
    elif _is(accel, 1.0, 4.0):
        sensor, steps = "accel", _six_sides("accel")
    elif _is(accel, 2.0):
        sensor, steps = "level", _simple("level")
    else:
        return Reply(MavResult.UNSUPPORTED, "Calibration: no supported sensor selected")
    v.ap.event(TruthEventKind.CALIBRATION, sensor=sensor)
    return Reply.accepted(*steps)
