"""Geofence and rally plans (MISSION_COUNT/ITEMs of mission_type FENCE and RALLY), as PX4.

A fence plan is made of inclusion and exclusion zones: polygons (a run of
NAV_FENCE_POLYGON_VERTEX_* items, each naming the vertex count in param1) and circles
(NAV_FENCE_CIRCLE_*, radius in param1). A point is inside the fence when it lies in at least
one inclusion zone (if there are any) and in no exclusion zone. In flight, leaving it
triggers GF_ACTION once per breach (0 none, 1 warning, 2 hold, 3 return, 4 terminate, 5 land);
arming outside it is refused unless GF_ACTION is 0. Rally points (NAV_RALLY_POINT) are where
RTL may go instead of home: the closest of home and the rally points, as PX4's RTL_TYPE 0.
Zones are kept in local ENU metres; the items are kept as uploaded for download.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from emulator.flight.mission import FRAMES_AMSL, FRAMES_RELATIVE, MissionItem
from emulator.flight.refusal import CommandRefused
from emulator.geo import GeoOrigin
from mavlink_vocabulary import MavCmd

__all__ = ["FENCE_COMMANDS", "RALLY_COMMANDS", "Fence", "Zone", "parse_fence", "parse_rally",
           "point_in_polygon"]

FENCE_COMMANDS = frozenset({
    MavCmd.NAV_FENCE_RETURN_POINT, MavCmd.NAV_FENCE_POLYGON_VERTEX_INCLUSION,
    MavCmd.NAV_FENCE_POLYGON_VERTEX_EXCLUSION, MavCmd.NAV_FENCE_CIRCLE_INCLUSION,
    MavCmd.NAV_FENCE_CIRCLE_EXCLUSION,
})
RALLY_COMMANDS = frozenset({MavCmd.NAV_RALLY_POINT})
_POLYGONS: dict[int, bool] = {MavCmd.NAV_FENCE_POLYGON_VERTEX_INCLUSION: True,
                              MavCmd.NAV_FENCE_POLYGON_VERTEX_EXCLUSION: False}
_CIRCLES: dict[int, bool] = {MavCmd.NAV_FENCE_CIRCLE_INCLUSION: True,
                             MavCmd.NAV_FENCE_CIRCLE_EXCLUSION: False}
Point = tuple[float, float]


def point_in_polygon(x: float, y: float, vertices: tuple[Point, ...]) -> bool:
    """Even-odd rule: whether (x, y) lies inside the polygon."""
    inside = False
    j = len(vertices) - 1
    for i, (xi, yi) in enumerate(vertices):
        xj, yj = vertices[j]
        if (yi > y) != (yj > y) and x < (xj - xi) * (y - yi) / (yj - yi) + xi:
            inside = not inside
        j = i
    return inside


@dataclass(frozen=True, slots=True)
class Zone:
    inclusion: bool
    vertices: tuple[Point, ...] = ()  # a polygon (ENU m), or
    center: Point = (0.0, 0.0)  # a circle's centre and radius
    radius_m: float = 0.0

    def contains(self, x: float, y: float) -> bool:
        if self.vertices:
            return point_in_polygon(x, y, self.vertices)
        return math.hypot(x - self.center[0], y - self.center[1]) <= self.radius_m


@dataclass(frozen=True, slots=True)
class Fence:
    zones: tuple[Zone, ...] = ()

    def contains(self, x: float, y: float) -> bool:
        """Inside at least one inclusion zone (if any) and inside no exclusion zone."""
        included = None
        for zone in self.zones:
            inside = zone.contains(x, y)
            if zone.inclusion:
                included = included or inside
            elif inside:
                return False
        return included is None or included


def _xy(item: MissionItem, origin: GeoOrigin, what: str) -> Point:
    if item.frame not in FRAMES_AMSL | FRAMES_RELATIVE:
        raise CommandRefused(f"{what}: frame {item.frame} unsupported")
    if not (-900_000_000 <= item.x <= 900_000_000 and -1_800_000_000 <= item.y <= 1_800_000_000):
        raise CommandRefused(f"{what}: latitude/longitude out of range")
    x, y, _ = origin.to_local(item.x * 1e-7, item.y * 1e-7, origin.altitude_amsl_m)
    return x, y


def parse_fence(items: list[MissionItem], origin: GeoOrigin) -> Fence:
    """The zones of a fence plan; CommandRefused (naming the item) if it is malformed."""
    zones: list[Zone] = []
    i = 0
    while i < len(items):
        item = items[i]
        what = f"Fence item {item.seq}"
        if item.command not in FENCE_COMMANDS:
            raise CommandRefused(f"{what}: command {item.command} is no fence item")
        if item.command in _POLYGONS:
            count = item.param1
            if not (math.isfinite(count) and count >= 3 and count == int(count)
                    and i + int(count) <= len(items)):
                raise CommandRefused(f"{what}: polygon vertex count {count:g} invalid")
            run = items[i:i + int(count)]
            if any(v.command != item.command or v.param1 != count for v in run):
                raise CommandRefused(f"{what}: polygon of {int(count)} vertices incomplete")
            zones.append(Zone(_POLYGONS[item.command],
                              tuple(_xy(v, origin, f"Fence item {v.seq}") for v in run)))
            i += int(count)
            continue
        if item.command in _CIRCLES:
            if not (math.isfinite(item.param1) and item.param1 > 0.0):
                raise CommandRefused(f"{what}: circle radius {item.param1:g} m invalid")
            zones.append(Zone(_CIRCLES[item.command], center=_xy(item, origin, what),
                              radius_m=item.param1))
        else:  # the return point: stored, not used by a multicopter
            _xy(item, origin, what)
        i += 1
    return Fence(tuple(zones))


def parse_rally(items: list[MissionItem], origin: GeoOrigin,
                home_m: tuple[float, float, float]) -> tuple[tuple[float, float, float], ...]:
    """The rally points of a rally plan (ENU m; altitude per the item's frame)."""
    points = []
    for item in items:
        what = f"Rally item {item.seq}"
        if item.command not in RALLY_COMMANDS:
            raise CommandRefused(f"{what}: command {item.command} is no rally point")
        x, y = _xy(item, origin, what)
        if math.isinf(item.z):
            raise CommandRefused(f"{what}: altitude is infinite")
        z = home_m[2] if math.isnan(item.z) else item.local_target_m(origin, home_m, home_m)[2]
        points.append((x, y, max(z, 0.0)))
    return tuple(points)
