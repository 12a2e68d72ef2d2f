"""The values every MAVLink fuzzer of the suite draws from: absurd and special floats, the
edges of every integer type, parameter names, command ids and the session origin.

tests/frame_fuzz.py (the seeded frame generator behind tests/test_fuzz.py,
tests/memory_fuzz.py and perf/protocol_fuzz.py) and tests/mavlink_strategies.py (the
Hypothesis strategies of tests/test_hardening_mavlink.py) both take their number ranges from
here, so a value added here reaches every fuzzer.
"""

from __future__ import annotations

import math

from emulator.flight.params import PARAM_DEFINITIONS
from emulator.geo import DEFAULT_ORIGIN
from emulator.mavlink.commands import HANDLERS
from mavlink_vocabulary import MavCmd

__all__ = ["ABSURD_FLOATS", "ALT0_M", "COMMANDS", "F32_MAX", "FAULT_PARAMS", "INT_RANGES",
           "LAT0_E7", "LON0_E7", "PARAM_NAMES", "SPECIAL_FLOATS", "UNKNOWN_COMMANDS",
           "int_edges"]

F32_MAX = 3.4028234663852886e38
# values no field should accept as they are (each is tried in every command parameter)
ABSURD_FLOATS = (
    math.nan, math.inf, -math.inf, F32_MAX, -F32_MAX, 1.4e-45, -1.4e-45, 0.0, -0.0,
    1.0, -1.0, -2.0, 2.0, 3.0, 4.0, 6.0, 1e30, -1e30, 2.0**31, -(2.0**31), 4294967295.0,
)
# the absurd ones and the round or meaningful ones a random value hardly ever is (modes,
# enum values, limits of smaller types)
SPECIAL_FLOATS = (*ABSURD_FLOATS, 0.5, 5.0, 10.0, 100.0, 1e6, -1e6, 21196.0, 65535.0, 1e-3)
INT_RANGES = {
    "uint8_t": (0, 255), "int8_t": (-128, 127), "uint16_t": (0, 65535),
    "int16_t": (-32768, 32767), "uint32_t": (0, 2**32 - 1), "int32_t": (-(2**31), 2**31 - 1),
    "uint64_t": (0, 2**64 - 1), "int64_t": (-(2**63), 2**63 - 1),
}


def int_edges(ftype: str) -> list[int]:
    """The edges of an integer type: its bounds, 0, +-1, 2, 255 and the middle."""
    lo, hi = INT_RANGES[ftype]
    return sorted({lo, hi, 0, min(1, hi), max(-1, lo), min(2, hi), min(255, hi), hi // 2})


# Parameters whose only effect makes a vehicle unfit to fly by design (a failed motor, a
# battery drained by a short endurance, a data-link failsafe): a fuzzer that must leave
# vehicles able to fly leaves them out (the hardening storm covers the faults' own).
FAULT_PARAMS = ("COM_DL_LOSS_T", "NAV_DLL_ACT", "SYS_FAILURE_EN", "SIM_HOVER_ENDUR")
PARAM_NAMES = tuple(d.name.encode() for d in PARAM_DEFINITIONS if d.name not in FAULT_PARAMS)
# ids no vehicle handles as a command: mission items sent as commands, unknown, reserved
UNKNOWN_COMMANDS = (MavCmd.NAV_WAYPOINT, MavCmd.NAV_LOITER_UNLIM, 183, 185, 246, 31000)
# every handled command but failure injection (a vehicle told to fail is not broken), those
# that make a vehicle move twice, and the unknown ones
COMMANDS = (*sorted(c for c in HANDLERS if c != MavCmd.INJECT_FAILURE),
            MavCmd.NAV_RETURN_TO_LAUNCH, MavCmd.NAV_LAND, MavCmd.NAV_TAKEOFF, MavCmd.DO_SET_MODE,
            *UNKNOWN_COMMANDS)
LAT0_E7 = round(DEFAULT_ORIGIN.latitude_deg * 1e7)
LON0_E7 = round(DEFAULT_ORIGIN.longitude_deg * 1e7)
ALT0_M = DEFAULT_ORIGIN.altitude_amsl_m
