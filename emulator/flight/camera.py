"""The vehicle's still camera: what a capture sees, recorded as ground truth."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from emulator.flight.battery import PHOTO_COST_PCT

if TYPE_CHECKING:
    from emulator.flight.autopilot import Autopilot

__all__ = ["ImageCapture", "capture_image"]


@dataclass(frozen=True, slots=True)
class ImageCapture:
    """One photo: where and when it was taken and the targets in its footprint."""

    index: int
    t_s: float
    position_m: tuple[float, float, float]
    yaw_deg: float
    targets: tuple[str, ...]


def capture_image(ap: Autopilot) -> ImageCapture:
    """Take a photo: the footprint is the vehicle's sensor disc (SIM_SENS_RAD)."""
    fleet, k = ap.fleet, ap.k
    position = ap.position_m
    others = {other.vehicle_id: other.position_m for other in fleet.autopilots if other.k != k}
    seen = fleet.sensor.sense(position, ap.params["SIM_SENS_RAD"], vehicles=others,
                              exclude_vehicle=ap.vehicle_id)
    ap.photo_count += 1
    fleet.bat.spend(k, PHOTO_COST_PCT)
    capture = ImageCapture(ap.photo_count, ap.now_s, position, float(fleet.dyn.yaw_deg[k]),
                           tuple(t.id for t in seen.targets))
    ap._event(
        "photo", index=capture.index, position_m=list(position), targets=list(capture.targets),
        obstacles=[o.id for o in seen.obstacles], vehicles=[v.id for v in seen.vehicles],
    )
    return capture
