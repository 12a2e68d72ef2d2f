"""The sensor model: what a vehicle perceives around it.

A target or obstacle is perceived when the horizontal distance from the vehicle to its geometry
(disc or polygon; 0 when inside, so a partly covered entity counts) is within the perceived
radius. Other vehicles are perceived by horizontal centre distance. No occlusion, noise or
latency. Results are sorted by distance, then id.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
import shapely

from emulator.target_motion import MovingTargets
from emulator.world import World

__all__ = ["VEHICLE_KIND", "Perception", "SensedEntity", "Sensor"]

VEHICLE_KIND = "vehicle"
_NO_VEHICLES: Mapping[str, tuple[float, float, float]] = MappingProxyType({})


@dataclass(frozen=True, slots=True)
class SensedEntity:
    """One perceived entity: its kind ('fixed', 'circle', ..., or 'vehicle') and where it is.

    An obstacle's position_m is its footprint centre at ground level.
    """

    id: str
    kind: str
    distance_m: float
    position_m: tuple[float, float, float]


@dataclass(frozen=True, slots=True)
class Perception:
    """Everything one vehicle perceives at one instant."""

    targets: tuple[SensedEntity, ...]
    obstacles: tuple[SensedEntity, ...]
    vehicles: tuple[SensedEntity, ...]


class _Layer:
    """Entities of one category behind an STRtree over their 2D geometries."""

    def __init__(self, geometries: list[shapely.Geometry],
                 entities: list[tuple[str, str, tuple[float, float, float]]]) -> None:
        self._geometries = np.array(geometries, dtype=object)
        self._entities = entities
        self._tree = shapely.STRtree(self._geometries)

    def within(self, point: shapely.Point, radius_m: float) -> tuple[SensedEntity, ...]:
        if not self._entities:
            return ()
        idx = self._tree.query(point, predicate="dwithin", distance=radius_m)
        if idx.size == 0:
            return ()
        distances = shapely.distance(self._geometries[idx], point).tolist()
        found = []
        for k, d in zip(idx.tolist(), distances, strict=True):
            ident, kind, position = self._entities[k]
            found.append(SensedEntity(ident, kind, d, position))
        found.sort(key=lambda s: (s.distance_m, s.id))
        return tuple(found)


class Sensor:
    """Perception queries over one world; the spatial indexes are built once."""

    def __init__(self, world: World, *, moving: MovingTargets | None = None) -> None:
        self._world = world
        self._moving = moving
        still = [t for t in world.targets if moving is None or t.id not in moving.ids]
        self._targets = _Layer(
            [t.geometry for t in still],
            [(t.id, t.kind, t.position_m) for t in still],
        )
        radii = {t.id: t.radius_m for t in world.targets}
        self._moving_radius_m = np.array([radii[i] for i in moving.ids]) if moving else None
        self._obstacles = _Layer(
            [o.footprint for o in world.obstacles],
            [(o.id, o.kind, (o.center_m[0], o.center_m[1], 0.0)) for o in world.obstacles],
        )

    @property
    def world(self) -> World:
        return self._world

    def sense(
        self,
        position_m: tuple[float, float, float],
        perceived_radius_m: float,
        *,
        vehicles: Mapping[str, tuple[float, float, float]] = _NO_VEHICLES,
        exclude_vehicle: str | None = None,
    ) -> Perception:
        """Targets, obstacles and other vehicles within perceived_radius_m (horizontal)."""
        if not (math.isfinite(perceived_radius_m) and perceived_radius_m >= 0.0):
            raise ValueError(f"perceived_radius_m must be >= 0, got {perceived_radius_m}")
        x, y = float(position_m[0]), float(position_m[1])
        point = shapely.Point(x, y)
        nearby: list[SensedEntity] = []
        for ident, other in vehicles.items():
            if ident == exclude_vehicle:
                continue
            d = math.hypot(other[0] - x, other[1] - y)
            if d <= perceived_radius_m:
                nearby.append(SensedEntity(
                    ident, VEHICLE_KIND, d, (float(other[0]), float(other[1]), float(other[2]))))
        nearby.sort(key=lambda s: (s.distance_m, s.id))
        return Perception(
            targets=self._with_moving(self._targets.within(point, perceived_radius_m), x, y,
                                      perceived_radius_m),
            obstacles=self._obstacles.within(point, perceived_radius_m),
            vehicles=tuple(nearby),
        )

    def _with_moving(self, found: tuple[SensedEntity, ...], x: float, y: float,
                     radius_m: float) -> tuple[SensedEntity, ...]:
        """Add the moving targets where they are now (their disc's distance)."""
        moving = self._moving
        if moving is None or self._moving_radius_m is None:
            return found
        xyz = moving.position_m
        d = np.maximum(np.hypot(xyz[:, 0] - x, xyz[:, 1] - y) - self._moving_radius_m, 0.0)
        extra = [SensedEntity(moving.ids[k], "moving", float(d[k]),
                              (float(xyz[k, 0]), float(xyz[k, 1]), float(xyz[k, 2])))
                 for k in np.flatnonzero(d <= radius_m)]
        if not extra:
            return found
        return tuple(sorted((*found, *extra), key=lambda s: (s.distance_m, s.id)))
