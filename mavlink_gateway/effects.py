"""What fresh telemetry shows of a command's effect: for a refusal that may answer a copy of
a command sent after an earlier copy acted (see mavlink_gateway.command_send)."""

from __future__ import annotations

from mavlink_gateway.drone_link import DroneLink
from mavlink_vocabulary import FlightState

__all__ = ["armed", "holding", "in_air", "landing", "returning"]

_DOWN = (FlightState.LANDING, FlightState.ON_GROUND)


def in_air(link: DroneLink) -> bool:
    """A take-off acted: the drone left the ground."""
    return link.flight_state != FlightState.ON_GROUND


def landing(link: DroneLink) -> bool:
    """A landing acted: the drone descends in LAND mode, or is down."""
    return link.mode == "LAND" or link.flight_state in _DOWN


def returning(link: DroneLink) -> bool:
    """A return to launch acted: RTL mode, its landing, or down."""
    return link.mode in ("RTL", "LAND") or link.flight_state in _DOWN


def armed(link: DroneLink) -> bool:
    return link.armed


def holding(link: DroneLink) -> bool:
    return link.mode == "HOLD"
