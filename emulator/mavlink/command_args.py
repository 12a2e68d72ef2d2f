"""One COMMAND_LONG or COMMAND_INT, normalised for the command handlers."""

from __future__ import annotations

import math
from dataclasses import dataclass

from emulator.mavlink.codec import mavlink

__all__ = ["INT32_MAX", "CommandArgs"]

INT32_MAX = 2**31 - 1


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
    frame: int  # altitude frame: AMSL (GLOBAL, GLOBAL_INT) or relative to home
    p5: float = math.nan  # param5 as sent (COMMAND_INT: x), for commands it is no latitude

    @classmethod
    def from_long(cls, m: mavlink.MAVLink_command_long_message) -> CommandArgs:
        lat = m.param5 if math.isfinite(m.param5) else None
        lon = m.param6 if math.isfinite(m.param6) else None
        return cls(m.command, m.param1, m.param2, m.param3, m.param4, lat, lon, m.param7, 0,
                   m.param5)

    @classmethod
    def from_int(cls, m: mavlink.MAVLink_command_int_message) -> CommandArgs:
        lat = None if m.x in (INT32_MAX, 0) and m.y in (INT32_MAX, 0) else m.x * 1e-7
        lon = None if lat is None else m.y * 1e-7
        return cls(m.command, m.param1, m.param2, m.param3, m.param4, lat, lon, m.z, m.frame,
                   float(m.x))
