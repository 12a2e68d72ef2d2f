"""Streamed pilot input: MANUAL_CONTROL (a joystick) -> the autopilot's manual control.

MANUAL_CONTROL carries x (pitch, forward), y (roll, right) and r (yaw, clockwise) in
[-1000, 1000] and z (thrust) in [0, 1000] with the centre at 500, as PX4 reads it from
QGroundControl's virtual joystick and MAVSDK; INT16_MAX marks an axis as invalid (read as
centred). A reading out of range is ignored as a whole: like the offboard set-points, each
function returns the problem as a `Complaint`, which the vehicle link reports once per kind.
"""

from __future__ import annotations

from emulator.flight.autopilot import Autopilot
from emulator.flight.manual_control import Sticks
from emulator.flight.refusal import CommandRefused
from emulator.mavlink.offboard import Complaint

__all__ = ["AXIS_INVALID", "apply_manual_control", "sticks_of"]

AXIS_INVALID = 32767  # INT16_MAX: the axis is not used
_FULL = 1000.0


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
