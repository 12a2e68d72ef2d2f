"""Body-frame vectors turned into the local ENU frame by a vehicle's heading."""

from __future__ import annotations

import math

__all__ = ["body_to_enu"]


def body_to_enu(yaw_deg: float, forward: float, right: float) -> tuple[float, float]:
    """Body forward/right -> (east, north) for a vehicle heading yaw_deg (0 north, 90 east)."""
    yaw = math.radians(yaw_deg)
    north = forward * math.cos(yaw) - right * math.sin(yaw)
    east = forward * math.sin(yaw) + right * math.cos(yaw)
    return east, north
