"""The five difficulty levels of the benchmark and the world parameters of each.

| level        | drones | targets: target_assignment / area families | obstacles | map (m)     |
|--------------|--------|--------------------------------------------|-----------|-------------|
| easy         | 3      | 5 / 3                                      | 6         | 600 x 600   |
| intermediate | 6      | 12 / 4                                     | 15        | 800 x 800   |
| moderate     | 10     | 25 / 6                                     | 30        | 1000 x 1000 |
| hard         | 16     | 50 / 8                                     | 60        | 1200 x 1200 |
| extreme      | 30     | 100 / 10                                   | 100       | 1500 x 1500 |

Target counts include the charging stations (1 at easy and intermediate, 2 above). Sizes are
half-extents: a disc's radius, an ellipse's larger semi-axis, a square's half side, a
rectangle's half length, a convex polygon's circumradius.

| level        | area targets (m) | obstacles (m) | obstacle shapes | base radius (m) |
|--------------|------------------|---------------|-----------------|-----------------|
| easy         | 30-60            | 8-40          | basic           | 35              |
| intermediate | 35-75            | 8-45          | all             | 40              |
| moderate     | 40-90            | 9-52          | all             | 45              |
| hard         | 45-105           | 10-60         | all             | 50              |
| extreme      | 50-120           | 10-70         | all             | 60              |

Basic obstacle shapes are circles and axis-aligned squares; "all" adds axis-aligned ellipses,
point obstacles, rotated rectangles and irregular convex polygons. Point obstacles are masts of
radius 2-5 m at every level, outside the size column.

Drones at easy, intermediate and moderate all have a 50 m perception radius and a 20 m task
radius; at hard and extreme each drone draws integers in 40-60 m and 15-25 m.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

__all__ = [
    "ALL_OBSTACLE_SHAPES",
    "BASIC_OBSTACLE_SHAPES",
    "LEVELS",
    "LEVEL_SPECS",
    "LevelSpec",
    "level_spec",
    "sized_spec",
]

LEVELS: tuple[str, ...] = ("easy", "intermediate", "moderate", "hard", "extreme")

BASIC_OBSTACLE_SHAPES: tuple[str, ...] = ("circle", "square")
ALL_OBSTACLE_SHAPES: tuple[str, ...] = (
    "circle", "square", "ellipse", "point", "rectangle", "convex",
)


@dataclass(frozen=True, slots=True)
class LevelSpec:
    """One row of the level table: entity counts, map size and size ranges of a level."""

    level: str
    drone_count: int
    target_assignment_target_count: int
    area_target_count: int
    obstacle_count: int
    map_width_m: int
    map_height_m: int
    charging_station_count: int
    area_size_m: tuple[float, float]
    obstacle_size_m: tuple[float, float]
    obstacle_shapes: tuple[str, ...]
    base_radius_m: float
    varied_sensor_radii: bool

    def target_count(self, area_family: bool) -> int:
        """Targets of a session of this level, charging stations included."""
        return self.area_target_count if area_family else self.target_assignment_target_count


LEVEL_SPECS: dict[str, LevelSpec] = {
    spec.level: spec
    for spec in (
        LevelSpec("easy", 3, 5, 3, 6, 600, 600, 1, (30.0, 60.0), (8.0, 40.0),
                  BASIC_OBSTACLE_SHAPES, 35.0, False),
        LevelSpec("intermediate", 6, 12, 4, 15, 800, 800, 1, (35.0, 75.0), (8.0, 45.0),
                  ALL_OBSTACLE_SHAPES, 40.0, False),
        LevelSpec("moderate", 10, 25, 6, 30, 1000, 1000, 2, (40.0, 90.0), (9.0, 52.0),
                  ALL_OBSTACLE_SHAPES, 45.0, False),
        LevelSpec("hard", 16, 50, 8, 60, 1200, 1200, 2, (45.0, 105.0), (10.0, 60.0),
                  ALL_OBSTACLE_SHAPES, 50.0, True),
        LevelSpec("extreme", 30, 100, 10, 100, 1500, 1500, 2, (50.0, 120.0), (10.0, 70.0),
                  ALL_OBSTACLE_SHAPES, 60.0, True),
    )
}


def level_spec(level: str) -> LevelSpec:
    """The table row of a level; raises ValueError naming an unknown level."""
    if not isinstance(level, str) or level not in LEVEL_SPECS:
        raise ValueError(f"level must be one of {', '.join(LEVELS)}; got {level!r}")
    return LEVEL_SPECS[level]


MAX_DRONES = 100
MAP_SIZE_RANGE_M = (200.0, 10000.0)


def sized_spec(spec: LevelSpec, drones: int = 0, map_size_m: float = 0.0) -> LevelSpec:
    """A level's row with another drone count and/or a square map of another side (0: the
    level's own); the base grows with the square root of the drone count. Raises ValueError
    naming the option."""
    if drones:
        if isinstance(drones, bool) or not isinstance(drones, int) or not (
                1 <= drones <= MAX_DRONES):
            raise ValueError(f"--drones must be a whole number from 1 to {MAX_DRONES}; "
                             f"got {drones!r}")
        grow = max(1.0, math.sqrt(drones / spec.drone_count))
        spec = dataclasses.replace(spec, drone_count=drones,
                                   base_radius_m=round(spec.base_radius_m * grow, 1))
    if map_size_m:
        low, high = MAP_SIZE_RANGE_M
        if not (isinstance(map_size_m, int | float) and low <= map_size_m <= high):
            raise ValueError(f"--map-size-m must be from {low:g} to {high:g} m; "
                             f"got {map_size_m!r}")
        side = int(map_size_m) if float(map_size_m).is_integer() else map_size_m
        spec = dataclasses.replace(spec, map_width_m=side, map_height_m=side)  # type: ignore[arg-type]
    return spec
