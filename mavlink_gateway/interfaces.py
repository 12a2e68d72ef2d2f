"""What the gateway needs from the side of the swarm that MAVLink does not carry, as protocols.

The gateway is a MAVLink client: it imports no emulator code. A swarm offers it a clock, each
drone's sensor feed, a radio and operator resets through an object satisfying `Services`
(the emulator's `SwarmServices` does); the local frame through any `GeoFrame`; and the drones'
limits through any `FleetSpec`.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Sequence
from typing import Any, Protocol

__all__ = ["FleetSpec", "GeoFrame", "Sensed", "SensedWorld", "Services", "VehicleSpec",
           "WorldWatch", "wrap_heading_deg"]


class GeoFrame(Protocol):
    """The local ENU frame's geodetic anchor."""

    def to_local(self, latitude_deg: float, longitude_deg: float, altitude_amsl_m: float
                 ) -> tuple[float, float, float]: ...

    def to_geodetic(self, x_m: float, y_m: float, z_m: float
                    ) -> tuple[float, float, float]: ...


class Sensed(Protocol):
    """One entity a drone's sensor perceives."""

    @property
    def id(self) -> str: ...
    @property
    def kind(self) -> str: ...
    @property
    def distance_m(self) -> float: ...
    @property
    def position_m(self) -> tuple[float, float, float]: ...


class SensedWorld(Protocol):
    """Everything one drone perceives at one instant."""

    @property
    def targets(self) -> Sequence[Sensed]: ...
    @property
    def obstacles(self) -> Sequence[Sensed]: ...
    @property
    def vehicles(self) -> Sequence[Sensed]: ...


class WorldWatch(Protocol):
    """A wait on the world under a lockstep clock: it halts (and pins the clock) when the
    watched drone's goal ends or a failsafe strikes it, at its deadline, or when a radio
    message for its drone can be read."""

    @property
    def at_deadline(self) -> bool: ...
    async def halted(self) -> float: ...
    def resume(self) -> None: ...
    def close(self) -> None: ...


class Services(Protocol):
    """A swarm's services besides MAVLink. The radio raises ValueError (with a readable
    message) for a message it refuses.

    `lockstep`: the swarm's clock runs only while every client waits on the world; clients
    then `pin` it while they think and `watch` while they wait (see mavlink_gateway.pacing)."""

    def clock_s(self) -> float: ...
    def clock_limit(self, t_s: float) -> contextlib.AbstractContextManager[None]: ...
    @property
    def lockstep(self) -> bool: ...
    def pin(self) -> object: ...
    def unpin(self, token: object) -> None: ...
    def refresh_telemetry(self, drone_id: str) -> None: ...
    def repeat_status_texts(self, drone_id: str) -> int: ...
    def watch(self, drone_id: str | None = None, *, until_s: float = math.inf,
              advance: bool = False, message_for: str | None = None) -> WorldWatch: ...
    async def advance(self, seconds: float) -> None: ...
    def sense(self, drone_id: str) -> SensedWorld: ...
    def send_message(self, sender: str, recipient: str, text: str) -> Any: ...
    def broadcast(self, sender: str, text: str) -> int: ...
    def read_messages(self, drone_id: str) -> list[Any]: ...
    def operator_land_all(self) -> None: ...
    def operator_reset_batteries(self, pct: float = 100.0) -> None: ...
    def operator_reset_to_start(self) -> None: ...


class VehicleSpec(Protocol):
    """A drone as its fleet owner knows it."""

    @property
    def id(self) -> str: ...
    @property
    def name(self) -> str: ...
    @property
    def max_altitude_m(self) -> float: ...
    @property
    def max_speed_m_s(self) -> float: ...
    @property
    def perceived_radius_m(self) -> float: ...
    @property
    def task_radius_m(self) -> float: ...


class FleetSpec(Protocol):
    """A fleet's drones, in MAVLink system-id order (system k + 1 is vehicles[k])."""

    @property
    def vehicles(self) -> Sequence[VehicleSpec]: ...


def wrap_heading_deg(heading_deg: float) -> float:
    """A heading in [0, 360)."""
    wrapped = math.fmod(heading_deg, 360.0)
    return wrapped + 360.0 if wrapped < 0.0 else wrapped
