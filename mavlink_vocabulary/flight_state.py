"""A drone's flight state as a ground station tells it from telemetry, and the one rule that
derives it: the MAV_LANDED_STATE of EXTENDED_SYS_STATE, whether the vehicle is in the air, and
its speed (slower than HOVER_SPEED_M_S in the air: hovering)."""

from __future__ import annotations

from enum import StrEnum

from mavlink_vocabulary.enums import MavLandedState

__all__ = ["HOVER_SPEED_M_S", "TELEMETRY_FLIGHT_STATES", "FlightState", "derive_flight_state"]

HOVER_SPEED_M_S = 0.5
"""Below this speed an airborne drone hovers (and a drone on the ground is at rest)."""


class FlightState(StrEnum):
    """What a drone is doing. The first five come from telemetry (`derive_flight_state`); a
    gateway also reports `failed` (the drone told of a failure that takes it out) and
    `unreachable` (no telemetry for a while: the rest of its state is as last seen)."""

    ON_GROUND = "on_ground"
    TAKING_OFF = "taking_off"
    HOVERING = "hovering"
    FLYING = "flying"
    LANDING = "landing"
    FAILED = "failed"
    UNREACHABLE = "unreachable"


TELEMETRY_FLIGHT_STATES: tuple[FlightState, ...] = (
    FlightState.ON_GROUND, FlightState.TAKING_OFF, FlightState.HOVERING, FlightState.FLYING,
    FlightState.LANDING)
"""The states `derive_flight_state` gives."""


def derive_flight_state(landed_state: int, in_air: bool, speed_m_s: float) -> FlightState:
    """The flight state of a vehicle whose landed state is `landed_state` (a MAV_LANDED_STATE
    value), that is (`in_air`) or is not in the air, moving at `speed_m_s`."""
    if landed_state == MavLandedState.ON_GROUND or not in_air:
        return FlightState.ON_GROUND
    if landed_state == MavLandedState.TAKEOFF:
        return FlightState.TAKING_OFF
    if landed_state == MavLandedState.LANDING:
        return FlightState.LANDING
    return FlightState.HOVERING if speed_m_s < HOVER_SPEED_M_S else FlightState.FLYING
