"""Flight modes and their PX4 custom_mode encoding (custom_mode = main << 16 | sub << 24)."""

from __future__ import annotations

from enum import Enum

__all__ = ["FlightMode", "LandedState", "decode_px4_mode"]

_MAIN_MANUAL, _MAIN_ALTCTL, _MAIN_POSCTL, _MAIN_AUTO = 1, 2, 3, 4
_MAIN_ACRO, _MAIN_OFFBOARD, _MAIN_STABILIZED = 5, 6, 7


class FlightMode(Enum):
    """A PX4 navigation mode: value is (main mode, sub mode)."""

    MANUAL = (_MAIN_MANUAL, 0)
    ALTCTL = (_MAIN_ALTCTL, 0)
    POSCTL = (_MAIN_POSCTL, 0)
    ACRO = (_MAIN_ACRO, 0)
    STABILIZED = (_MAIN_STABILIZED, 0)
    OFFBOARD = (_MAIN_OFFBOARD, 0)
    READY = (_MAIN_AUTO, 1)
    TAKEOFF = (_MAIN_AUTO, 2)
    HOLD = (_MAIN_AUTO, 3)
    MISSION = (_MAIN_AUTO, 4)
    RTL = (_MAIN_AUTO, 5)
    LAND = (_MAIN_AUTO, 6)
    FOLLOW_TARGET = (_MAIN_AUTO, 8)
    ORBIT = (_MAIN_POSCTL, 1)  # PX4 reports orbit as POSCTL's ORBIT sub mode

    @property
    def custom_mode(self) -> int:
        main, sub = self.value
        return (main << 16) | (sub << 24)

    @property
    def label(self) -> str:
        return self.name.lower()


class LandedState(Enum):
    """MAV_LANDED_STATE values."""

    ON_GROUND = 1
    IN_AIR = 2
    TAKEOFF = 3
    LANDING = 4


_BY_VALUE = {m.value: m for m in FlightMode}


def decode_px4_mode(main: int, sub: int) -> FlightMode | None:
    """The mode a DO_SET_MODE (p2 = main, p3 = sub) asks for, or None if it is no PX4 mode."""
    if main == _MAIN_AUTO:
        return _BY_VALUE.get((main, sub))
    return _BY_VALUE.get((main, 0))
