"""Streamed pilot input: MANUAL_CONTROL (a joystick) -> the autopilot's manual control, and
FOLLOW_TARGET (where the target to follow is) -> its follow-target mode.

MANUAL_CONTROL carries x (pitch, forward), y (roll, right) and r (yaw, clockwise) in
[-1000, 1000] and z (thrust) in [0, 1000] with the centre at 500, as PX4 reads it from
QGroundControl's virtual joystick and MAVSDK; INT16_MAX marks an axis as invalid (read as
centred). FOLLOW_TARGET carries the target's position (degE7, AMSL m) and velocity (NED m/s;
NaN reads as 0); as PX4, its est_capabilities are not read (MAVSDK sends the velocity with
only the position bit set). A reading out of range is ignored as a whole: like the offboard
set-points, each function returns the problem as a `Complaint`, which the vehicle link
reports once per kind.
"""

from __future__ import annotations

import math

from emulator.flight.autopilot import Autopilot
from emulator.flight.manual_control import Sticks
from emulator.flight.refusal import CommandRefused
from emulator.mavlink.offboard import Complaint

__all__ = ["AXIS_INVALID", "MAX_TARGET_SPEED_M_S", "apply_follow_target", "apply_manual_control",
           "sticks_of"]

AXIS_INVALID = 32767  # INT16_MAX: the axis is not used
_FULL = 1000.0
MAX_TARGET_SPEED_M_S = 100.0  # a target reported faster than this is no fix


def sticks_of(m) -> Sticks | Complaint:
    """The normalised sticks of one MANUAL_CONTROL, or why it is ignored."""
    values = []
    for name, low, centre in (("x", -_FULL, 0.0), ("y", -_FULL, 0.0), ("z", 0.0, 500.0),
                              ("r", -_FULL, 0.0)):
        raw = getattr(m, name)
        if raw == AXIS_INVALID:
            raw = centre
        elif not low <= raw <= _FULL:
            return Complaint(f"manual_{name}",
                             f"Joystick {name} {raw} outside [{low:g}, {_FULL:g}]: ignored")
        values.append(raw)
    x, y, z, r = values
    return Sticks(x / _FULL, y / _FULL, (z - 500.0) / 500.0, r / _FULL)


def apply_manual_control(ap: Autopilot, m, wall_now_s: float) -> Complaint | None:
    sticks = sticks_of(m)
    if isinstance(sticks, Complaint):
        return sticks
    try:
        ap.manual.input(sticks, wall_now_s)
    except CommandRefused as refusal:
        return Complaint("manual_mode", str(refusal))
    return None


def apply_follow_target(ap: Autopilot, m, wall_now_s: float) -> Complaint | None:
    lat, lon, alt = m.lat / 1e7, m.lon / 1e7, m.alt
    if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0 and -1e3 <= alt <= 1e5):
        return Complaint("follow_position", "Follow target: position out of range ignored")
    north, east, down = (float(v) if math.isfinite(v) else 0.0 for v in m.vel)
    if max(abs(north), abs(east), abs(down)) > MAX_TARGET_SPEED_M_S:
        return Complaint("follow_velocity", "Follow target: velocity out of range ignored")
    x, y, z = ap.fleet.world.origin.to_local(lat, lon, alt)
    ap.follow.update((x, y, z), (east, north, -down), wall_now_s)
    return None
