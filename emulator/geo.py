"""Local ENU metres <-> WGS84 geodetic coordinates.

The world frame is a flat local tangent plane: x east, y north, z up (metres above the
ground at the origin). One :class:`GeoOrigin` per session anchors it to latitude, longitude
and altitude (AMSL). The conversion uses the WGS84 radii of curvature at the origin, which is
exact at the origin and within centimetres over the few kilometres a mission spans.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["DEFAULT_ORIGIN", "GeoOrigin", "heading_deg_from_vector", "wrap_heading_deg"]

_WGS84_A_M = 6378137.0
_WGS84_E2 = 6.69437999014e-3


@dataclass(frozen=True, slots=True)
class GeoOrigin:
    """Geodetic anchor of the local frame: the point x = y = z = 0."""

    latitude_deg: float
    longitude_deg: float
    altitude_amsl_m: float = 0.0

    def __post_init__(self) -> None:
        for name in ("latitude_deg", "longitude_deg", "altitude_amsl_m"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"origin {name} must be a finite number")
        if not -89.0 <= self.latitude_deg <= 89.0:
            raise ValueError(f"origin latitude {self.latitude_deg} outside [-89, 89] degrees")
        if not -180.0 <= self.longitude_deg <= 180.0:
            raise ValueError(f"origin longitude {self.longitude_deg} outside [-180, 180] degrees")

    @property
    def metres_per_rad(self) -> tuple[float, float]:
        """(east metres per radian of longitude, north metres per radian of latitude)."""
        lat = math.radians(self.latitude_deg)
        s2 = math.sin(lat) ** 2
        denom = 1.0 - _WGS84_E2 * s2
        prime_vertical_m = _WGS84_A_M / math.sqrt(denom)
        meridian_m = _WGS84_A_M * (1.0 - _WGS84_E2) / denom**1.5
        return prime_vertical_m * math.cos(lat), meridian_m

    def to_geodetic(self, x_m: float, y_m: float, z_m: float) -> tuple[float, float, float]:
        """Local ENU metres -> (latitude_deg, longitude_deg, altitude_amsl_m)."""
        east_per_rad, north_per_rad = self.metres_per_rad
        lat = self.latitude_deg + math.degrees(y_m / north_per_rad)
        lon = self.longitude_deg + math.degrees(x_m / east_per_rad)
        return lat, lon, self.altitude_amsl_m + z_m

    def to_local(
        self, latitude_deg: float, longitude_deg: float, altitude_amsl_m: float
    ) -> tuple[float, float, float]:
        """(latitude_deg, longitude_deg, altitude_amsl_m) -> local ENU metres."""
        east_per_rad, north_per_rad = self.metres_per_rad
        x = math.radians(longitude_deg - self.longitude_deg) * east_per_rad
        y = math.radians(latitude_deg - self.latitude_deg) * north_per_rad
        return x, y, altitude_amsl_m - self.altitude_amsl_m

    def scale(self) -> tuple[float, float]:
        """(degrees of longitude per east metre, degrees of latitude per north metre)."""
        east_per_rad, north_per_rad = self.metres_per_rad
        return math.degrees(1.0 / east_per_rad), math.degrees(1.0 / north_per_rad)


# PX4 SITL's customary home (Zurich), used when a session names no origin.
DEFAULT_ORIGIN = GeoOrigin(47.397742, 8.545594, 488.0)


def wrap_heading_deg(heading_deg: float) -> float:
    """Normalise a heading to [0, 360)."""
    wrapped = math.fmod(heading_deg, 360.0)
    return wrapped + 360.0 if wrapped < 0.0 else wrapped


def heading_deg_from_vector(dx_m: float, dy_m: float) -> float:
    """Compass bearing (clockwise from north) of an ENU displacement; 0 for a null vector."""
    if dx_m == 0.0 and dy_m == 0.0:
        return 0.0
    return wrap_heading_deg(math.degrees(math.atan2(dx_m, dy_m)))
