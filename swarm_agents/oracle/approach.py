"""Where the oracle starts a leg the straight way would not allow: a directed leg blocked where
the drone stands, and a goal closer to an obstacle than the path planner's clearance (the
reference's placeholders keep waypoints only 1 m off obstacles; collision prevention stops a
drone 2 m short, within the usual 3 m tolerance)."""

from __future__ import annotations

import math

import shapely
import shapely.ops

from swarm_agents.oracle.planner import NoPath, PathPlanner

__all__ = ["approach_point", "leg_start", "reachable"]

Point3 = tuple[float, float, float]

LEG_RING_M = 15.0  # directed legs: rings of spots around the drone
LEG_RINGS = 20
LEG_SLACK_M = 15.0
APPROACH_RINGS_M = (10.0, 14.0, 18.0, 24.0, 32.0)  # goals near an obstacle: spots around it
RING_SPOTS = 16


def reachable(planner: PathPlanner, here: Point3, goal: Point3) -> bool:
    """Whether the planner finds a path from here to goal."""
    try:
        planner.plan(here, goal)
    except NoPath:
        return False
    return True


def _ring(x: float, y: float, r: float) -> list[tuple[float, float]]:
    return [(x + r * math.cos(2.0 * math.pi * k / RING_SPOTS),
             y + r * math.sin(2.0 * math.pi * k / RING_SPOTS)) for k in range(RING_SPOTS)]


def leg_start(planner: PathPlanner, here: Point3, heading_deg: float, distance_m: float
              ) -> tuple[float, float]:
    """Where a straight leg of distance_m on heading_deg can start: here when nothing blocks
    it, else the nearest reachable spot (rings of LEG_RING_M) whose leg, with some slack,
    collision prevention lets through; here again when there is none."""
    h = math.radians(heading_deg)
    dx, dy = math.sin(h), math.cos(h)
    x, y, z = here

    def clear(sx: float, sy: float, length_m: float) -> bool:
        return planner.leg_clear((sx, sy, z), (sx + length_m * dx, sy + length_m * dy, z))

    if clear(x, y, distance_m):
        return x, y
    for ring in range(1, LEG_RINGS + 1):
        for sx, sy in _ring(x, y, ring * LEG_RING_M):
            if clear(sx, sy, distance_m + LEG_SLACK_M) and reachable(planner, here, (sx, sy, z)):
                return sx, sy
    return x, y


def _away_from_obstacle(planner: PathPlanner, x: float, y: float
                        ) -> tuple[float, float] | None:
    """The unit vector from the nearest obstacle's edge to (x, y): a straight approach along
    it meets the safety margin nearest the point."""
    point = shapely.Point(x, y)
    obstacles = planner.world.obstacles
    if not obstacles:
        return None
    nearest = min(obstacles, key=lambda o: o.footprint.distance(point))
    edge = shapely.ops.nearest_points(nearest.footprint.boundary, point)[0]
    dx, dy = x - edge.x, y - edge.y
    if nearest.footprint.contains(point):
        dx, dy = -dx, -dy
    norm = math.hypot(dx, dy)
    return None if norm < 1e-9 else (dx / norm, dy / norm)


def approach_point(planner: PathPlanner, here: Point3, goal: Point3) -> Point3 | None:
    """A reachable spot near a goal the planner cannot reach (too close to an obstacle) from
    which the straight line to the goal is open until collision prevention stops the drone:
    on the line from the nearest obstacle through the goal, else on rings around the goal;
    None when there is none."""
    gx, gy, gz = goal
    normal = _away_from_obstacle(planner, gx, gy)
    for r in APPROACH_RINGS_M:
        ahead = [] if normal is None else [(gx + r * normal[0], gy + r * normal[1])]
        for sx, sy in ahead + _ring(gx, gy, r):
            spot = (sx, sy, gz)
            if reachable(planner, here, spot):
                return spot
    return None
