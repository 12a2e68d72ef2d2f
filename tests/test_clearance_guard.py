"""The clearance guard's distance to the nearest obstacle volume: measured exactly against
only the obstacles near by their bounds, it equals the distance to every obstacle."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from emulator.flight.collision import FEW_OBSTACLES, ClearanceGuard
from emulator.world import Obstacle, World


def _world(rng: np.random.Generator, count: int) -> World:
    obstacles = []
    for i in range(count):
        cx, cy = rng.uniform(-400.0, 400.0, 2).tolist()
        height = 0.0 if i % 4 == 0 else float(rng.uniform(5.0, 60.0))
        if i % 3 == 0:
            obstacles.append(Obstacle.disc(f"o{i}", "disc", (cx, cy),
                                           float(rng.uniform(3.0, 30.0)), height_m=height))
        else:
            w, h = rng.uniform(4.0, 50.0, 2).tolist()
            obstacles.append(Obstacle.polygon(
                f"o{i}", "box", [(cx, cy), (cx + w, cy), (cx + w * 0.7, cy + h), (cx, cy + h)],
                height_m=height))
    return World(obstacles=obstacles)


def _every_obstacle_m(world: World, x: float, y: float, z: float) -> float:
    """The distance to each obstacle volume, the smallest."""
    best = math.inf
    for o in world.obstacles:
        d_xy = float(shapely.distance(o.footprint, shapely.Point(x, y)))
        above = max(0.0, z - o.height_m) if o.height_m > 0.0 else 0.0
        best = min(best, math.sqrt(d_xy * d_xy + above * above))
    return best


@pytest.mark.parametrize("count", [60, FEW_OBSTACLES, 3])  # numpy's passes, Python floats
def test_clearance_is_the_distance_to_the_nearest_of_all_obstacles(count: int) -> None:
    rng = np.random.default_rng(7)
    world = _world(rng, count)
    guard = ClearanceGuard(world, 1)
    points = [tuple(p) for p in np.column_stack((rng.uniform(-450, 450, (1500, 2)),
                                                 rng.uniform(-1, 80, 1500))).tolist()]
    # on vertices, inside footprints, just above and below a top
    for o in world.obstacles[:20]:
        vx, vy = shapely.get_coordinates(o.footprint)[0].tolist()
        c = o.footprint.representative_point()
        points += [(vx, vy, 1.0), (c.x, c.y, 2.0), (c.x, c.y, o.height_m + 0.5),
                   (c.x, c.y, o.height_m)]
    got = [guard.clearance_m(*p) for p in points]
    want = [_every_obstacle_m(world, *p) for p in points]
    assert got == want  # the same floats, not approximately
    assert any(d == 0.0 for d in got)  # some points lie inside a volume


def test_no_obstacles_no_limit() -> None:
    assert ClearanceGuard(World(), 2).clearance_m(0.0, 0.0, 10.0) == math.inf
