"""What every primitive returns: a status, one readable line, and the drone's state after."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from enum import StrEnum
from typing import Any

from mavlink_vocabulary import FlightState

__all__ = ["RESERVED_KEYS", "DroneState", "Outcome", "Status"]

RESERVED_KEYS = frozenset({"status", "message", "state"})
"""The keys of an outcome's own fields in `Outcome.to_dict`; its data never uses them."""


class Status(StrEnum):
    OK = "ok"  # done as asked
    PARTIAL = "partial"  # part of it done (e.g. some waypoints of a path)
    BLOCKED = "blocked"  # stopped by the world: an obstacle, a battery failsafe
    REJECTED = "rejected"  # refused before anything was sent: nothing changed
    TIMEOUT = "timeout"  # the simulated-time budget ran out
    UNKNOWN = "unknown"  # no answer came (a lossy link, a silent drone): it may have acted
    FAILED = "failed"  # the drone reported a failure (a motor, its GPS): it is out
    INTERRUPTED = "interrupted"  # ended early by a hold or a new goal that replaced it


@dataclass(frozen=True, slots=True)
class DroneState:
    """A drone as its own telemetry reports it (local ENU metres, compass heading)."""

    drone: str
    x_m: float
    y_m: float
    altitude_m: float
    heading_deg: float
    battery_pct: float
    # on_ground, taking_off, hovering, flying, landing; failed (a motor or GPS failure
    # reported), unreachable (no telemetry for a while: the state is as last seen)
    flight_state: FlightState
    armed: bool
    mode: str
    home_x_m: float = math.nan
    home_y_m: float = math.nan

    @property
    def position_m(self) -> tuple[float, float, float]:
        return self.x_m, self.y_m, self.altitude_m

    def to_dict(self) -> dict[str, Any]:
        """The state as JSON-ready values; a quantity telemetry has not told yet (NaN) is None,
        which JSON carries as null: unknown, never a number."""
        d = asdict(self)
        for key in ("x_m", "y_m", "altitude_m", "heading_deg", "battery_pct", "home_x_m",
                    "home_y_m"):
            d[key] = None if math.isnan(d[key]) else round(d[key], 2)
        return d

    def describe(self) -> str:
        return (f"{self.drone} {self.flight_state} at ({self.x_m:.1f}, {self.y_m:.1f}, "
                f"{self.altitude_m:.1f}) heading {self.heading_deg:.0f} deg, "
                f"battery {self.battery_pct:.0f}%")


@dataclass(frozen=True, slots=True)
class Outcome:
    status: Status
    message: str
    state: DroneState | None = None
    data: dict[str, Any] | None = None

    def __post_init__(self) -> None:
        clash = RESERVED_KEYS.intersection(self.data or ())
        if clash:  # to_dict would let the data replace the outcome's own fields
            raise ValueError(f"an outcome's data may not use the key(s) {sorted(clash)}")

    @property
    def ok(self) -> bool:
        return self.status is Status.OK

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"status": self.status.value, "message": self.message}
        if self.state is not None:
            d["state"] = self.state.to_dict()
        if self.data:
            d.update(self.data)
        return d
