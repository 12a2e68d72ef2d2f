"""MAVLink vocabulary shared by the emulator, the gateway and the tests.

Named IntEnums for the MAVLink numbers the code uses, each member spelled as in the pymavlink
common dialect without its enum's prefix (`MavCmd.NAV_TAKEOFF` is `MAV_CMD_NAV_TAKEOFF`;
tests/test_mavlink_vocabulary.py checks every value against the dialect), and the STATUSTEXT
reasons a ground station reads to tell why a vehicle stopped or refused, and the flight state
a ground station derives from telemetry (`FlightState`, `derive_flight_state`).

This is the bottom layer: it imports nothing of mavswarm (and not even pymavlink).
"""

from mavlink_vocabulary.enums import (
    CameraCapFlags,
    FailureType,
    FailureUnit,
    GpsFixType,
    MavAutopilot,
    MavBatteryChargeState,
    MavBatteryFunction,
    MavBatteryType,
    MavComponent,
    MavFrame,
    MavLandedState,
    MavMissionResult,
    MavMissionType,
    MavModeFlag,
    MavParamType,
    MavProtocolCapability,
    MavResult,
    MavSeverity,
    MavState,
    MavSysStatusSensor,
    MavType,
    MavVtolState,
    PositionTargetTypemask,
    SpeedType,
)
from mavlink_vocabulary.flight_state import (
    HOVER_SPEED_M_S,
    TELEMETRY_FLIGHT_STATES,
    FlightState,
    derive_flight_state,
)
from mavlink_vocabulary.ids import MavCmd, MessageId
from mavlink_vocabulary.reasons import (
    FAILSAFE_TEXTS,
    FAILURE_TEXTS,
    OBSTACLE_TEXT,
    REPAIRED_TEXT,
)

__all__ = [
    "FAILSAFE_TEXTS",
    "FAILURE_TEXTS",
    "HOVER_SPEED_M_S",
    "OBSTACLE_TEXT",
    "REPAIRED_TEXT",
    "TELEMETRY_FLIGHT_STATES",
    "CameraCapFlags",
    "FailureType",
    "FailureUnit",
    "FlightState",
    "GpsFixType",
    "MavAutopilot",
    "MavBatteryChargeState",
    "MavBatteryFunction",
    "MavBatteryType",
    "MavCmd",
    "MavComponent",
    "MavFrame",
    "MavLandedState",
    "MavMissionResult",
    "MavMissionType",
    "MavModeFlag",
    "MavParamType",
    "MavProtocolCapability",
    "MavResult",
    "MavSeverity",
    "MavState",
    "MavSysStatusSensor",
    "MavType",
    "MavVtolState",
    "MessageId",
    "PositionTargetTypemask",
    "SpeedType",
    "derive_flight_state",
]
