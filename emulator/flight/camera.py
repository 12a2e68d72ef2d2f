"""The vehicle's still camera: what a capture sees, recorded as ground truth."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from emulator.flight.battery import PHOTO_COST_PCT
from emulator.flight.fleet_view import FleetView
from emulator.flight.params import ParamStore
from emulator.truth_events import TruthEventKind

__all__ = ["CameraCarrier", "ImageCapture", "capture_image"]


@dataclass(frozen=True, slots=True)
class ImageCapture:
    """One photo: where and when it was taken and the targets in its footprint."""

    index: int
    t_s: float
    position_m: tuple[float, float, float]
    yaw_deg: float
    targets: tuple[str, ...]


class CameraCarrier(Protocol):
    """The vehicle a camera is on (the autopilot)."""

    @property
    def k(self) -> int: ...
    @property
    def vehicle_id(self) -> str: ...
    @property
    def fleet(self) -> FleetView: ...
    @property
    def params(self) -> ParamStore: ...
    @property
    def position_m(self) -> tuple[float, float, float]: ...
    @property
    def now_s(self) -> float: ...
    def event(self, kind: TruthEventKind, **data: object) -> None: ...


def _position(fleet: FleetView, k: int) -> tuple[float, float, float]:
    p = fleet.dyn.position_m[k]
    return float(p[0]), float(p[1]), float(p[2])


def capture_image(ap: CameraCarrier, index: int) -> ImageCapture:
    """Take photo number `index`: the footprint is the vehicle's sensor disc (SIM_SENS_RAD)."""
    fleet, k = ap.fleet, ap.k
    position = ap.position_m
    others = {vid: _position(fleet, j) for vid, j in fleet.index_by_id.items() if j != k}
    seen = fleet.sensor.sense(position, ap.params["SIM_SENS_RAD"], vehicles=others,
                              exclude_vehicle=ap.vehicle_id)
    fleet.bat.spend(k, PHOTO_COST_PCT)
    capture = ImageCapture(index, ap.now_s, position, float(fleet.dyn.yaw_deg[k]),
                           tuple(t.id for t in seen.targets))
    ap.event(
        TruthEventKind.PHOTO, index=capture.index, position_m=list(position),
        targets=list(capture.targets),
        obstacles=[o.id for o in seen.obstacles], vehicles=[v.id for v in seen.vehicles],
    )
    return capture
