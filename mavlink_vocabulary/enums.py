"""IntEnums of the MAVLink common dialect: the members mavswarm uses, named as pymavlink
names them without the enum's prefix (values checked against the dialect by
tests/test_mavlink_vocabulary.py)."""

from __future__ import annotations

from enum import IntEnum, IntFlag

__all__ = [
    "CameraCapFlags",
    "FailureType",
    "FailureUnit",
    "GpsFixType",
    "MavAutopilot",
    "MavBatteryChargeState",
    "MavBatteryFunction",
    "MavBatteryType",
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
    "PositionTargetTypemask",
    "SpeedType",
]


class MavResult(IntEnum):
    """MAV_RESULT_*: a COMMAND_ACK's result."""

    ACCEPTED = 0
    TEMPORARILY_REJECTED = 1
    DENIED = 2
    UNSUPPORTED = 3
    FAILED = 4


class MavMissionResult(IntEnum):
    """MAV_MISSION_*: a MISSION_ACK's type."""

    ACCEPTED = 0
    ERROR = 1
    UNSUPPORTED_FRAME = 2
    UNSUPPORTED = 3
    NO_SPACE = 4
    INVALID = 5
    INVALID_PARAM1 = 6
    INVALID_PARAM2 = 7
    INVALID_PARAM3 = 8
    INVALID_PARAM4 = 9
    INVALID_PARAM5_X = 10
    INVALID_PARAM6_Y = 11
    INVALID_PARAM7 = 12
    INVALID_SEQUENCE = 13
    DENIED = 14
    OPERATION_CANCELLED = 15


class MavMissionType(IntEnum):
    """MAV_MISSION_TYPE_*."""

    MISSION = 0
    FENCE = 1
    RALLY = 2
    ALL = 255


class MavFrame(IntEnum):
    """MAV_FRAME_*."""

    GLOBAL = 0
    LOCAL_NED = 1
    MISSION = 2
    GLOBAL_RELATIVE_ALT = 3
    LOCAL_ENU = 4
    GLOBAL_INT = 5
    GLOBAL_RELATIVE_ALT_INT = 6
    LOCAL_OFFSET_NED = 7
    BODY_NED = 8
    BODY_OFFSET_NED = 9
    GLOBAL_TERRAIN_ALT = 10
    GLOBAL_TERRAIN_ALT_INT = 11
    BODY_FRD = 12


class MavType(IntEnum):
    """MAV_TYPE_*."""

    GENERIC = 0
    QUADROTOR = 2
    GCS = 6
    GIMBAL = 26
    CAMERA = 30


class MavAutopilot(IntEnum):
    """MAV_AUTOPILOT_*."""

    GENERIC = 0
    INVALID = 8
    PX4 = 12


class MavComponent(IntEnum):
    """MAV_COMP_ID_*."""

    ALL = 0
    AUTOPILOT1 = 1
    CAMERA = 100
    GIMBAL = 154
    MISSIONPLANNER = 190


class MavModeFlag(IntFlag):
    """MAV_MODE_FLAG_*: a HEARTBEAT's base mode bits."""

    CUSTOM_MODE_ENABLED = 1
    TEST_ENABLED = 2
    AUTO_ENABLED = 4
    GUIDED_ENABLED = 8
    STABILIZE_ENABLED = 16
    HIL_ENABLED = 32
    MANUAL_INPUT_ENABLED = 64
    SAFETY_ARMED = 128


class MavState(IntEnum):
    """MAV_STATE_*: a HEARTBEAT's system status."""

    UNINIT = 0
    BOOT = 1
    CALIBRATING = 2
    STANDBY = 3
    ACTIVE = 4
    CRITICAL = 5
    EMERGENCY = 6
    POWEROFF = 7
    FLIGHT_TERMINATION = 8


class MavLandedState(IntEnum):
    """MAV_LANDED_STATE_*."""

    UNDEFINED = 0
    ON_GROUND = 1
    IN_AIR = 2
    TAKEOFF = 3
    LANDING = 4


class MavSeverity(IntEnum):
    """MAV_SEVERITY_*: a STATUSTEXT's severity."""

    EMERGENCY = 0
    ALERT = 1
    CRITICAL = 2
    ERROR = 3
    WARNING = 4
    NOTICE = 5
    INFO = 6
    DEBUG = 7


class MavParamType(IntEnum):
    """MAV_PARAM_TYPE_*."""

    UINT8 = 1
    INT8 = 2
    UINT16 = 3
    INT16 = 4
    UINT32 = 5
    INT32 = 6
    UINT64 = 7
    INT64 = 8
    REAL32 = 9
    REAL64 = 10


class MavProtocolCapability(IntFlag):
    """MAV_PROTOCOL_CAPABILITY_*: AUTOPILOT_VERSION's capabilities."""

    MISSION_FLOAT = 1
    PARAM_FLOAT = 2
    MISSION_INT = 4
    COMMAND_INT = 8
    PARAM_ENCODE_BYTEWISE = 16
    FTP = 32
    SET_ATTITUDE_TARGET = 64
    SET_POSITION_TARGET_LOCAL_NED = 128
    SET_POSITION_TARGET_GLOBAL_INT = 256
    MAVLINK2 = 8192


class MavSysStatusSensor(IntFlag):
    """MAV_SYS_STATUS_SENSOR_*: SYS_STATUS's sensor bits."""

    SENSOR_3D_GYRO = 0x1
    SENSOR_3D_ACCEL = 0x2
    SENSOR_3D_MAG = 0x4
    SENSOR_ABSOLUTE_PRESSURE = 0x8
    SENSOR_GPS = 0x20
    SENSOR_ANGULAR_RATE_CONTROL = 0x400
    SENSOR_ATTITUDE_STABILIZATION = 0x800
    SENSOR_YAW_POSITION = 0x1000
    SENSOR_Z_ALTITUDE_CONTROL = 0x2000
    SENSOR_XY_POSITION_CONTROL = 0x4000
    SENSOR_MOTOR_OUTPUTS = 0x8000
    GEOFENCE = 0x100000
    AHRS = 0x200000
    SENSOR_BATTERY = 0x2000000
    PREARM_CHECK = 0x10000000


class MavBatteryChargeState(IntEnum):
    """MAV_BATTERY_CHARGE_STATE_*."""

    UNDEFINED = 0
    OK = 1
    LOW = 2
    CRITICAL = 3
    EMERGENCY = 4
    FAILED = 5
    UNHEALTHY = 6
    CHARGING = 7


class FailureUnit(IntEnum):
    """FAILURE_UNIT_*: what MAV_CMD_INJECT_FAILURE breaks."""

    SENSOR_GPS = 4
    SYSTEM_BATTERY = 100
    SYSTEM_MOTOR = 101
    SYSTEM_MAVLINK_SIGNAL = 105


class FailureType(IntEnum):
    """FAILURE_TYPE_*."""

    OK = 0
    OFF = 1


class PositionTargetTypemask(IntFlag):
    """POSITION_TARGET_TYPEMASK_*: the fields a set-point ignores."""

    X_IGNORE = 1
    Y_IGNORE = 2
    Z_IGNORE = 4
    VX_IGNORE = 8
    VY_IGNORE = 16
    VZ_IGNORE = 32
    AX_IGNORE = 64
    AY_IGNORE = 128
    AZ_IGNORE = 256
    FORCE_SET = 512
    YAW_IGNORE = 1024
    YAW_RATE_IGNORE = 2048


class CameraCapFlags(IntFlag):
    """CAMERA_CAP_FLAGS_*."""

    CAPTURE_VIDEO = 1
    CAPTURE_IMAGE = 2
    HAS_MODES = 4
    CAN_CAPTURE_IMAGE_IN_VIDEO_MODE = 8
    HAS_VIDEO_STREAM = 256


class GpsFixType(IntEnum):
    """GPS_FIX_TYPE_*."""

    NO_GPS = 0
    NO_FIX = 1
    FIX_2D = 2
    FIX_3D = 3


class MavBatteryFunction(IntEnum):
    """MAV_BATTERY_FUNCTION_*."""

    UNKNOWN = 0
    ALL = 1


class MavBatteryType(IntEnum):
    """MAV_BATTERY_TYPE_*."""

    UNKNOWN = 0
    LIPO = 1


class MavVtolState(IntEnum):
    """MAV_VTOL_STATE_*."""

    UNDEFINED = 0
    MC = 3


class SpeedType(IntEnum):
    """SPEED_TYPE_*: MAV_CMD_DO_CHANGE_SPEED's param1."""

    AIRSPEED = 0
    GROUNDSPEED = 1
    CLIMB_SPEED = 2
    DESCENT_SPEED = 3
