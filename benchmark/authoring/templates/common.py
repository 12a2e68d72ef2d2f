"""Small helpers shared by the template modules: distances, names, homes and visit checks."""

from __future__ import annotations

import math
import random
from collections.abc import Sequence
from pathlib import Path

from benchmark.authoring.templates.base import SessionView, TemplateUnfit, fmt_xy, leaf
from emulator.scenario import VehicleSpec
from emulator.world import Target

__all__ = ["FILES", "diagonal_m", "home_xy", "inspectable", "names", "nearest_first",
           "spread_points", "target_xy", "visited"]

Point = tuple[float, float]

FILES = Path(__file__).resolve().parent / "files"
"""The built-in templates written as template files (benchmark.authoring.template_files)."""


def spread_points(view: SessionView, rng: random.Random, n: int, min_gap_m: float,
                  side_m: float, tries: int = 60) -> list[Point]:
    """n free points at least min_gap_m apart inside one random square of side side_m (or the
    map less a 30 m margin, where the map is smaller)."""
    sx = min(side_m, view.map_w_m - 60.0)
    sy = min(side_m, view.map_h_m - 60.0)
    for _ in range(tries):
        x0 = rng.uniform(30.0, view.map_w_m - 30.0 - sx)
        y0 = rng.uniform(30.0, view.map_h_m - 30.0 - sy)
        points: list[Point] = []
        for _ in range(20 * n):
            p = view.free_point(rng, region=(x0, y0, x0 + sx, y0 + sy))
            if all(math.dist(p, q) >= min_gap_m for q in points):
                points.append(p)
                if len(points) == n:
                    return points
    raise TemplateUnfit(f"no {n} free points {min_gap_m:.0f} m apart")


def diagonal_m(view: SessionView) -> float:
    return math.hypot(view.map_w_m, view.map_h_m)


def target_xy(t: Target) -> str:
    return fmt_xy(t.position_m[0], t.position_m[1])


def names(items: Sequence[VehicleSpec | Target]) -> str:
    """ "A", "A and B", "A, B and C"."""
    labels = [item.name for item in items]
    return labels[0] if len(labels) == 1 else ", ".join(labels[:-1]) + " and " + labels[-1]


def inspectable(view: SessionView, k: int) -> list[Target]:
    """Fixed point targets and area targets: those a drone can fly over and photograph."""
    pool = [t for t in view.points if t.kind == "fixed"] + list(view.areas)
    if len(pool) < k:
        raise TemplateUnfit(f"needs {k} fixed or area targets, the session has {len(pool)}")
    return pool


def nearest_first(start: Point, points: Sequence[Point]) -> list[Point]:
    """points in nearest-neighbour order from start."""
    left, order, here = list(points), [], start
    while left:
        here = min(left, key=lambda p: math.dist(here, p))
        left.remove(here)
        order.append(here)
    return order


def home_xy(view: SessionView, drone_index: int) -> Point:
    home = view.drones[drone_index].home_m
    return float(home[0]), float(home[1])


def visited(drone_id: str, points: Sequence[Point], alt: int) -> list[dict]:
    return [leaf("drone_has_visited_position", drone_id=drone_id, x=x, y=y, z=float(alt),
                 tolerance=3.0) for x, y in points]
