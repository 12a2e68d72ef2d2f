"""The PX4-named parameter set each emulated vehicle exposes and obeys.

Only parameters the emulator really uses are listed: changing one changes the flight. Values
are validated against their range before they are stored, so a bad PARAM_SET changes nothing.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass

__all__ = [
    "PARAM_DEFINITIONS", "PARAM_ID_MAX_CHARS", "ParamDefinition", "ParamError", "ParamStore",
]


PARAM_ID_MAX_CHARS = 16  # PARAM_VALUE.param_id is char[16]


class ParamError(ValueError):
    """Raised when a parameter name is unknown or a value is outside its range."""


@dataclass(frozen=True, slots=True)
class ParamDefinition:
    name: str
    default: float
    minimum: float
    maximum: float
    is_int: bool = False
    description: str = ""

    def __post_init__(self) -> None:
        if not 0 < len(self.name) <= PARAM_ID_MAX_CHARS:
            raise ValueError(f"parameter name {self.name!r}: 1 to {PARAM_ID_MAX_CHARS} chars")


def _p(name: str, default: float, lo: float, hi: float, desc: str, *,
       is_int: bool = False) -> ParamDefinition:
    return ParamDefinition(name, default, lo, hi, is_int, desc)


PARAM_DEFINITIONS: tuple[ParamDefinition, ...] = (
    _p("MIS_TAKEOFF_ALT", 10.0, 1.0, 120.0, "takeoff altitude above home when none is given (m)"),
    _p("MPC_XY_CRUISE", 8.0, 0.5, 30.0, "default horizontal speed in missions and goto (m/s)"),
    _p("MPC_XY_VEL_MAX", 12.0, 0.5, 30.0, "maximum horizontal airspeed (m/s)"),
    _p("MPC_Z_VEL_MAX_UP", 3.0, 0.5, 8.0, "maximum climb rate (m/s)"),
    _p("MPC_Z_VEL_MAX_DN", 1.5, 0.5, 4.0, "maximum descent rate (m/s)"),
    _p("MPC_TKO_SPEED", 1.5, 0.5, 5.0, "takeoff climb rate (m/s)"),
    _p("MPC_LAND_SPEED", 0.7, 0.2, 2.0, "final landing descent rate (m/s)"),
    _p("MPC_LAND_ALT2", 5.0, 0.0, 50.0, "altitude below which landing slows to MPC_LAND_SPEED (m)"),
    _p("MPC_THR_HOVER", 0.5, 0.1, 0.8, "hover thrust (normalised) of attitude set-points"),
    _p("MPC_ACC_HOR", 3.0, 0.5, 15.0, "horizontal acceleration limit (m/s^2)"),
    _p("MPC_ACC_UP_MAX", 4.0, 0.5, 15.0, "vertical acceleration limit (m/s^2)"),
    _p("MPC_YAWRAUTO_MAX", 45.0, 5.0, 360.0, "yaw rate limit in auto modes (deg/s)"),
    _p("MC_YAWRATE_MAX", 200.0, 5.0, 1800.0, "offboard yaw-rate set-point limit (deg/s)"),
    _p("MC_ORBIT_RAD_MAX", 1000.0, 1.0, 10000.0, "largest orbit radius (m)"),
    _p("MC_ORBIT_YAW_MOD", 0, 0, 4, "orbit yaw behaviour when none is given", is_int=True),
    _p("FLW_TGT_HT", 8.0, 8.0, 120.0, "follow-target height above home or the target (m)"),
    _p("FLW_TGT_DST", 8.0, 1.0, 100.0, "follow-target horizontal distance (m)"),
    _p("FLW_TGT_FA", 180.0, -180.0, 180.0, "follow angle from the target's course (deg, "
       "0 front, 90 right, 180 behind)"),
    _p("FLW_TGT_RS", 0.1, 0.0, 1.0, "follow-target estimate lag (s): 0 follows each fix"),
    _p("FLW_TGT_ALT_M", 0, 0, 2, "follow-target altitude: 0 above home, 1 terrain (flat: "
       "as 0), 2 above the target", is_int=True),
    _p("FLW_TGT_MAX_VEL", 5.0, 0.0, 20.0, "speed circling the target to the follow angle (m/s)"),
    _p("NAV_ACC_RAD", 2.0, 0.05, 200.0, "acceptance radius of waypoints and goto (m)"),
    _p("RTL_RETURN_ALT", 30.0, 0.0, 150.0, "minimum altitude for the return leg of RTL (m)"),
    _p("COM_DISARM_LAND", 2.0, -1.0, 20.0, "auto-disarm delay after landing (s, -1 off)"),
    _p("COM_DISARM_PRFLT", 10.0, -1.0, 60.0, "auto-disarm delay when armed without takeoff (s)"),
    _p("COM_OF_LOSS_T", 1.0, 0.1, 60.0, "offboard setpoint loss timeout (wall s)"),
    _p("CP_DIST", 2.0, 0.0, 15.0, "collision prevention: stop distance before obstacles (m)"),
    _p("GF_MAX_VER_DIST", 120.0, 1.0, 10000.0, "altitude ceiling above home (m)"),
    _p("GF_ACTION", 2, 0, 5, "geofence breach action: 0 none, 1 warn, 2 hold, 3 return, "
       "4 terminate, 5 land", is_int=True),
    _p("GF_MAX_HOR_DIST", 10000.0, 10.0, 100000.0, "maximum horizontal distance from home (m)"),
    _p("BAT_LOW_THR", 0.15, 0.12, 0.5, "low battery warning threshold (fraction)"),
    _p("BAT_CRIT_THR", 0.07, 0.05, 0.5, "critical battery threshold: return home (fraction)"),
    _p("BAT_EMERGEN_THR", 0.05, 0.03, 0.5, "emergency battery threshold: land (fraction)"),
    _p("BAT_CAPACITY", 5000.0, 100.0, 100000.0, "battery capacity (mAh)"),
    _p("BAT_N_CELLS", 4, 1, 14, "number of cells in series", is_int=True),
    _p("BAT_V_CHARGED", 4.2, 3.5, 4.5, "cell voltage when full (V)"),
    _p("BAT_V_EMPTY", 3.5, 2.5, 4.0, "cell voltage when empty (V)"),
    _p("SIM_HOVER_ENDUR", 1200.0, 60.0, 36000.0, "hover endurance on a full battery (s)"),
    _p("SIM_SENS_RAD", 50.0, 1.0, 10000.0, "sensor (perceived) radius (m)"),
    _p("SIM_TASK_RAD", 20.0, 0.1, 10000.0, "task radius (m)"),
    _p("SIM_HOME_MAXDIST", 10000.0, 10.0, 100000.0,
       "maximum horizontal distance of home from the session origin (m)"),
    _p("MAV_SYS_ID", 1, 1, 250, "MAVLink system id", is_int=True),
    _p("MAV_TYPE", 2, 0, 50, "MAVLink vehicle type (2 = quadrotor)", is_int=True),
    _p("SYS_AUTOSTART", 10016, 0, 9999999, "airframe id (SITL quadrotor)", is_int=True),
    _p("SYS_HITL", 0, 0, 2, "hardware in the loop", is_int=True),
    _p("CAL_ACC0_ID", 1310988, 0, 2**31 - 1, "accelerometer calibration id", is_int=True),
    _p("CAL_GYRO0_ID", 1310988, 0, 2**31 - 1, "gyro calibration id", is_int=True),
    _p("CAL_MAG0_ID", 197388, 0, 2**31 - 1, "magnetometer calibration id", is_int=True),
    _p("COM_RC_IN_MODE", 3, 0, 4, "manual control source: 0 RC only, 1 joystick (MAVLink) "
       "only, 2 RC and joystick, 3 RC or joystick keep first, 4 stick input disabled",
       is_int=True),
    _p("COM_RC_LOSS_T", 0.5, 0.0, 35.0, "manual control loss timeout (wall s)"),
    _p("NAV_RCL_ACT", 2, 0, 3, "manual control loss action in POSCTL/ALTCTL: 0 centre the "
       "sticks, 1 hold, 2 return, 3 land", is_int=True),
    _p("MPC_VEL_MANUAL", 10.0, 1.0, 20.0, "POSCTL horizontal speed at full stick (m/s)"),
    _p("MPC_MAN_TILT_MAX", 35.0, 1.0, 60.0, "ALTCTL tilt at full stick (deg)"),
    _p("MPC_MAN_Y_MAX", 150.0, 0.0, 400.0, "yaw rate at full stick (deg/s)"),
    _p("MPC_HOLD_DZ", 0.1, 0.0, 0.9, "stick deadzone around the centre (fraction)"),
    _p("COM_DL_LOSS_T", 10.0, 5.0, 300.0, "data link loss time-out (simulated s)"),
    _p("NAV_DLL_ACT", 0, 0, 3, "data link loss action: 0 none, 1 hold, 2 return, 3 land",
       is_int=True),
    _p("SYS_FAILURE_EN", 0, 0, 1, "accept MAV_CMD_INJECT_FAILURE (failure injection)",
       is_int=True),
)

_BY_NAME: dict[str, ParamDefinition] = {d.name: d for d in PARAM_DEFINITIONS}


class ParamStore(Mapping[str, float]):
    """One vehicle's parameter values, in definition order (PARAM_VALUE index order)."""

    __slots__ = ("_values",)

    def __init__(self, overrides: Mapping[str, float] | None = None) -> None:
        self._values: dict[str, float] = {d.name: float(d.default) for d in PARAM_DEFINITIONS}
        for name, value in (overrides or {}).items():
            self.set(name, value)

    def __getitem__(self, name: str) -> float:
        return self._values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    @staticmethod
    def definition(name: str) -> ParamDefinition:
        try:
            return _BY_NAME[name]
        except KeyError:
            raise ParamError(f"unknown parameter {name!r}") from None

    @staticmethod
    def index_of(name: str) -> int:
        return list(_BY_NAME).index(name)

    @staticmethod
    def name_at(index: int) -> str:
        if not 0 <= index < len(PARAM_DEFINITIONS):
            raise ParamError(f"parameter index {index} outside 0..{len(PARAM_DEFINITIONS) - 1}")
        return PARAM_DEFINITIONS[index].name

    def set(self, name: str, value: float) -> float:
        """Validate and store a value; returns the stored value. Raises ParamError."""
        d = self.definition(name)
        if not isinstance(value, int | float) or not math.isfinite(value):
            raise ParamError(f"{name}: value must be a finite number, got {value!r}")
        if d.is_int:
            if value != int(value):
                raise ParamError(f"{name}: integer parameter, got {value}")
            value = int(value)
        if not d.minimum <= value <= d.maximum:
            raise ParamError(f"{name}: {value:g} outside [{d.minimum:g}, {d.maximum:g}]")
        self._values[name] = float(value)
        return float(value)
