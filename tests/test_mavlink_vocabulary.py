"""The shared MAVLink vocabulary matches the pymavlink common dialect, member by member."""

from __future__ import annotations

import enum

import pytest
from pymavlink.dialects.v20 import common as mavlink

import mavlink_vocabulary as vocab

# enum class -> (pymavlink enum name, prefix of its entries)
DIALECT_ENUMS: dict[type[enum.Enum], tuple[str, str]] = {
    vocab.MavCmd: ("MAV_CMD", "MAV_CMD_"),
    vocab.MavResult: ("MAV_RESULT", "MAV_RESULT_"),
    vocab.MavMissionResult: ("MAV_MISSION_RESULT", "MAV_MISSION_"),
    vocab.MavMissionType: ("MAV_MISSION_TYPE", "MAV_MISSION_TYPE_"),
    vocab.MavFrame: ("MAV_FRAME", "MAV_FRAME_"),
    vocab.MavType: ("MAV_TYPE", "MAV_TYPE_"),
    vocab.MavAutopilot: ("MAV_AUTOPILOT", "MAV_AUTOPILOT_"),
    vocab.MavComponent: ("MAV_COMPONENT", "MAV_COMP_ID_"),
    vocab.MavModeFlag: ("MAV_MODE_FLAG", "MAV_MODE_FLAG_"),
    vocab.MavState: ("MAV_STATE", "MAV_STATE_"),
    vocab.MavLandedState: ("MAV_LANDED_STATE", "MAV_LANDED_STATE_"),
    vocab.MavSeverity: ("MAV_SEVERITY", "MAV_SEVERITY_"),
    vocab.MavParamType: ("MAV_PARAM_TYPE", "MAV_PARAM_TYPE_"),
    vocab.MavProtocolCapability: ("MAV_PROTOCOL_CAPABILITY", "MAV_PROTOCOL_CAPABILITY_"),
    vocab.MavSysStatusSensor: ("MAV_SYS_STATUS_SENSOR", "MAV_SYS_STATUS_"),
    vocab.MavBatteryChargeState: ("MAV_BATTERY_CHARGE_STATE", "MAV_BATTERY_CHARGE_STATE_"),
    vocab.FailureUnit: ("FAILURE_UNIT", "FAILURE_UNIT_"),
    vocab.FailureType: ("FAILURE_TYPE", "FAILURE_TYPE_"),
    vocab.PositionTargetTypemask: ("POSITION_TARGET_TYPEMASK", "POSITION_TARGET_TYPEMASK_"),
    vocab.CameraCapFlags: ("CAMERA_CAP_FLAGS", "CAMERA_CAP_FLAGS_"),
    vocab.GpsFixType: ("GPS_FIX_TYPE", "GPS_FIX_TYPE_"),
    vocab.MavBatteryFunction: ("MAV_BATTERY_FUNCTION", "MAV_BATTERY_FUNCTION_"),
    vocab.MavBatteryType: ("MAV_BATTERY_TYPE", "MAV_BATTERY_TYPE_"),
    vocab.MavVtolState: ("MAV_VTOL_STATE", "MAV_VTOL_STATE_"),
    vocab.SpeedType: ("SPEED_TYPE", "SPEED_TYPE_"),
}


# dialect names that are no Python identifier once their prefix is gone
RENAMED = {"GPS_FIX_TYPE_2D_FIX": "FIX_2D", "GPS_FIX_TYPE_3D_FIX": "FIX_3D"}


@pytest.mark.parametrize("cls", list(DIALECT_ENUMS), ids=lambda c: c.__name__)
def test_every_member_has_the_dialects_name_and_value(cls: type[enum.Enum]) -> None:
    name, prefix = DIALECT_ENUMS[cls]
    entries = mavlink.enums[name]
    for member in cls:
        assert member.value in entries, f"{cls.__name__}.{member.name}"
        dialect = entries[member.value].name
        assert RENAMED.get(dialect, dialect) in (prefix + member.name, member.name), member


def test_message_ids_are_the_dialects() -> None:
    for member in vocab.MessageId:
        assert getattr(mavlink, f"MAVLINK_MSG_ID_{member.name}") == member.value, member
        assert mavlink.mavlink_map[member.value].msgname == member.name


# The vocabulary's own words, not MAVLink's (tested in test_flight_state.py and
# test_statustext.py)
OWN_ENUMS: set[type[enum.Enum]] = {vocab.FlightState, vocab.BatteryLevel, vocab.FailsafeAction,
                                   vocab.GeofenceAction}


def test_every_exported_enum_is_checked() -> None:
    exported = {getattr(vocab, n) for n in vocab.__all__}
    enums = {c for c in exported if isinstance(c, type) and issubclass(c, enum.Enum)}
    assert enums == set(DIALECT_ENUMS) | {vocab.MessageId} | OWN_ENUMS


def test_the_flight_logics_mavlink_tables_agree_with_the_vocabulary() -> None:
    from emulator.flight.limits import SpeedKind
    from emulator.flight.mission import Cmd, MissionResult
    from emulator.flight.modes import LandedState
    from emulator.flight.refusal import Severity
    from emulator.mavlink.mission_transfer import wire_result

    def members(table: object) -> dict[str, int]:
        return {k: int(v) for k, v in vars(table).items()
                if k.isupper() and isinstance(v, int | enum.Enum)}

    for name, value in members(Cmd).items():
        assert vocab.MavCmd[name] == value, name
    for name, value in members(Severity).items():
        assert vocab.MavSeverity[name] == value, name
    for state in LandedState:
        assert vocab.MavLandedState[state.name] == state.value, state
    assert [int(k) for k in SpeedKind] == [int(t) for t in vocab.SpeedType]
    # the mission results go out as the dialect's member of the same name
    for name, value in members(MissionResult).items():
        assert wire_result(value) is vocab.MavMissionResult[name], name
