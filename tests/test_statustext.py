"""STATUSTEXT messages: one builder, one parser, the emulator writes through the first and the
gateway and the MQTT bus read through the second."""

from __future__ import annotations

import ast
import typing
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from mavlink_vocabulary import (
    GOAL_ENDING_MESSAGES,
    OUT_OF_TASK_MESSAGES,
    STATUSTEXT_MAX_CHARS,
    Announcement,
    BatteryFailsafe,
    BatteryFailure,
    BatteryLevel,
    DataLinkLost,
    FailsafeAction,
    FailuresCleared,
    FreeText,
    GeofenceAction,
    GeofenceBreached,
    GeofenceReached,
    GpsLost,
    LowBattery,
    ManualControlLost,
    MotorFailure,
    ObstacleHold,
    OffboardLost,
    build_statustext,
    parse_statustext,
)
from mqtt_bus.payloads import statustext_event

ROOT = Path(__file__).resolve().parents[1]

whole_pct = st.integers(-5, 1000).map(float)
announcements: dict[type, st.SearchStrategy[Announcement]] = {
    ObstacleHold: st.builds(ObstacleHold, st.text(min_size=1)),
    LowBattery: st.builds(LowBattery, whole_pct),
    BatteryFailsafe: st.builds(BatteryFailsafe, st.sampled_from(BatteryLevel), whole_pct),
    OffboardLost: st.just(OffboardLost()),
    GeofenceReached: st.just(GeofenceReached()),
    GeofenceBreached: st.builds(GeofenceBreached, st.sampled_from(GeofenceAction)),
    DataLinkLost: st.builds(DataLinkLost, st.sampled_from(FailsafeAction)),
    ManualControlLost: st.builds(ManualControlLost,
                                 st.none() | st.sampled_from(FailsafeAction)),
    MotorFailure: st.builds(MotorFailure, st.booleans()),
    GpsLost: st.builds(GpsLost, st.booleans()),
    BatteryFailure: st.builds(BatteryFailure, whole_pct),
    FailuresCleared: st.just(FailuresCleared()),
}
any_announcement = st.one_of(*announcements.values())


def test_every_kind_of_message_is_drawn() -> None:
    assert set(announcements) == set(typing.get_args(Announcement))


@given(any_announcement)
def test_round_trip(message: Announcement) -> None:
    assert parse_statustext(build_statustext(message)) == message


@given(any_announcement, st.floats(allow_nan=False, allow_infinity=False,
                                   min_value=-0.4, max_value=100.0))
def test_a_fractional_percent_reads_back_as_sent(message: Announcement, pct: float) -> None:
    if hasattr(message, "pct"):
        message = type(message)(**{**{f: getattr(message, f) for f in message.__match_args__},
                                   "pct": pct})
    text = build_statustext(message)
    assert build_statustext(parse_statustext(text)) == text


@given(st.text())
def test_parsing_keeps_every_text(text: str) -> None:
    """Whatever a vehicle says reads back to the same text (FreeText when no type fits)."""
    if len(text) == STATUSTEXT_MAX_CHARS and text.startswith("Obstacle "):
        return  # a cut obstacle hold: its own test
    assert build_statustext(parse_statustext(text)) == text


@pytest.mark.parametrize(("text", "expected"), [
    ("Obstacle Tower A ahead: holding", ObstacleHold("Tower A")),
    ("Critical battery 14%: returning home", BatteryFailsafe(BatteryLevel.CRITICAL, 14.0)),
    ("Emergency battery 5%: landing", BatteryFailsafe(BatteryLevel.EMERGENCY, 5.0)),
    ("Critical battery 14%: landing", FreeText("Critical battery 14%: landing")),
    ("Geofence breached", GeofenceBreached(GeofenceAction.WARN)),
    ("Geofence breached: flight terminated", GeofenceBreached(GeofenceAction.TERMINATE)),
    ("Manual control lost: failsafe sticks centred", ManualControlLost(None)),
    ("GPS lost: no position estimate", GpsLost(landing=False)),
    ("Landing detected", FreeText("Landing detected")),
    ("Arming denied: motor failure", FreeText("Arming denied: motor failure")),
])
def test_texts_as_sent(text: str, expected: object) -> None:
    assert parse_statustext(text) == expected


def test_severities() -> None:
    assert BatteryFailsafe(BatteryLevel.EMERGENCY, 3.0).severity == 2
    assert GeofenceBreached(GeofenceAction.TERMINATE).severity == 2
    assert GeofenceBreached(GeofenceAction.HOLD).severity == 4
    assert MotorFailure(falling=True).severity == 0 and FailuresCleared().severity == 6


def test_a_hold_cut_on_the_wire_keeps_its_kind() -> None:
    text = build_statustext(ObstacleHold("a very long obstacle name from the scenario"))
    cut = text[:STATUSTEXT_MAX_CHARS]
    assert isinstance(parse_statustext(cut), ObstacleHold)
    assert statustext_event("d1", 1.0, 4, cut)["kind"] == "obstacle_hold"


def test_what_ends_a_goal_and_what_takes_a_drone_out() -> None:
    ends = {t for t in announcements if issubclass(t, GOAL_ENDING_MESSAGES)}
    out = {t for t in announcements if issubclass(t, OUT_OF_TASK_MESSAGES)}
    assert ends == {BatteryFailsafe, OffboardLost, DataLinkLost}
    assert out == {MotorFailure, GpsLost}


@given(any_announcement)
def test_the_bus_classifies_what_the_parser_reads(message: Announcement) -> None:
    event = statustext_event("d1", 2.0, int(message.severity), build_statustext(message))
    kind = {ObstacleHold: "obstacle_hold", BatteryFailsafe: "failsafe",
            OffboardLost: "failsafe", GeofenceReached: "failsafe"}.get(type(message),
                                                                        "statustext")
    assert event["kind"] == kind


FRAGMENTS = ("ahead: holding", "Critical battery", "Emergency battery", "Low battery",
             "setpoints lost", "Geofence reached", "Geofence breached", "Data link lost",
             "Manual control lost", "Motor failure:", "GPS lost:", "Battery failure",
             "Failures cleared")


def test_the_emulator_writes_through_the_builder() -> None:
    written = []
    for path in sorted((ROOT / "emulator").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and \
                    any(f in node.value for f in FRAGMENTS) and not _docstring_like(node.value):
                written.append(f"{path.relative_to(ROOT)}:{node.lineno}: {node.value}")
    assert written == []


def _docstring_like(value: str) -> bool:
    return len(value) > 60 or "\n" in value
