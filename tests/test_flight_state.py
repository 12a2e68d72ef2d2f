"""One flight state, derived by one rule from one hover speed, wherever a package tells it."""

from __future__ import annotations

import ast
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st
from mavsdk.plugins.telemetry import LandedState as TelemetryLandedState

from emulator.flight.modes import LandedState as EmulatorLandedState
from mavlink_gateway.drone_link import DroneLink
from mavlink_vocabulary import (
    HOVER_SPEED_M_S,
    TELEMETRY_FLIGHT_STATES,
    FlightState,
    MavLandedState,
    derive_flight_state,
)

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("mavlink_vocabulary", "emulator", "mavlink_gateway", "agent_contract", "llm_tools",
            "mqtt_bus", "benchmark", "console", "mavswarm")


@pytest.mark.parametrize(("landed", "in_air", "speed_m_s", "expected"), [
    (MavLandedState.ON_GROUND, True, 3.0, FlightState.ON_GROUND),
    (MavLandedState.IN_AIR, False, 3.0, FlightState.ON_GROUND),
    (MavLandedState.TAKEOFF, True, 3.0, FlightState.TAKING_OFF),
    (MavLandedState.LANDING, True, 0.0, FlightState.LANDING),
    (MavLandedState.IN_AIR, True, HOVER_SPEED_M_S - 0.01, FlightState.HOVERING),
    (MavLandedState.IN_AIR, True, HOVER_SPEED_M_S, FlightState.FLYING),
    (MavLandedState.UNDEFINED, True, 0.1, FlightState.HOVERING),
])
def test_rule(landed: MavLandedState, in_air: bool, speed_m_s: float,
              expected: FlightState) -> None:
    assert derive_flight_state(landed, in_air, speed_m_s) is expected


@given(st.sampled_from(MavLandedState), st.booleans(),
       st.floats(min_value=0.0, max_value=100.0))
def test_derived_states_are_the_telemetry_ones(landed: MavLandedState, in_air: bool,
                                                speed_m_s: float) -> None:
    state = derive_flight_state(int(landed), in_air, speed_m_s)
    assert state in TELEMETRY_FLIGHT_STATES
    assert state is derive_flight_state(landed, in_air, speed_m_s)


def test_values_are_the_published_words() -> None:
    assert [s.value for s in FlightState] == [
        "on_ground", "taking_off", "hovering", "flying", "landing", "failed", "unreachable"]
    assert FlightState.FLYING == "flying" and f"{FlightState.FLYING}" == "flying"


def _assigned_names(path: Path) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        targets = node.targets if isinstance(node, ast.Assign) else (
            [node.target] if isinstance(node, ast.AnnAssign) else [])
        names.update(t.id for t in targets if isinstance(t, ast.Name))
    return names


def test_one_hover_speed() -> None:
    defining = sorted(str(p.relative_to(ROOT)) for package in PACKAGES
                      for p in (ROOT / package).rglob("*.py")
                      if "HOVER_SPEED_M_S" in _assigned_names(p))
    assert defining == ["mavlink_vocabulary/flight_state.py"]


@given(st.sampled_from(list(TelemetryLandedState)), st.booleans(),
       st.floats(min_value=0.0, max_value=20.0))
def test_the_gateway_reads_mavsdk_landed_states_as_the_rule(landed: Any, in_air: bool,
                                                              speed_m_s: float) -> None:
    """The gateway keeps MAVSDK's landed-state names; its flight state is the rule's for the
    MAV_LANDED_STATE they stand for (the bus's swarm view passes the emulator's values)."""
    link = SimpleNamespace(landed_state=landed.name, in_air=in_air, speed_m_s=speed_m_s)
    derived = DroneLink.flight_state.fget(link)  # type: ignore[attr-defined]
    assert derived is derive_flight_state(landed.value, in_air, speed_m_s)


def test_the_emulators_landed_states_are_mavlinks() -> None:
    assert {m.name: m.value for m in EmulatorLandedState} == {
        "ON_GROUND": MavLandedState.ON_GROUND, "IN_AIR": MavLandedState.IN_AIR,
        "TAKEOFF": MavLandedState.TAKEOFF, "LANDING": MavLandedState.LANDING}
