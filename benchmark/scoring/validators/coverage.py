"""Coverage of targets and task progress over a window.

Area targets (circle, polygon): the fraction of the footprint's area inside the union of the
corridors swept by every drone, a corridor being the drone's airborne flight path (simplified
by SIMPLIFY_M) buffered by its task radius. Point-type targets: 1.0 when some drone reached
them, else 0.0. Charging stations (waypoint targets) never count towards task progress.
"""

from __future__ import annotations

import math

import numpy as np
import shapely

from benchmark.scoring.validators.context import CheckContext
from benchmark.scoring.validators.reach import flight_path, visits

__all__ = [
    "AREA_TASK_TYPES",
    "DONE_COVERAGE",
    "SIMPLIFY_M",
    "TRACKING_WINDOW_S",
    "corridor_lines",
    "coverage",
    "reached_by_any",
    "task_done",
    "task_progress",
]

SIMPLIFY_M = 0.5
DONE_COVERAGE = 0.9
AREA_TASK_TYPES = ("area_search", "area_assignment_and_patrol")
_BUFFER_QUAD_SEGS = 8


def corridor_lines(ctx: CheckContext, drone_id: str) -> np.ndarray:
    """The drone's airborne flight path as simplified lines (or points), an object array."""
    def make() -> np.ndarray:
        path = flight_path(ctx, drone_id)
        pieces = []
        for first, last in path.chains(np.ones(path.size, dtype=bool)):
            coords = path.coordinates(first, last)
            if np.all(coords == coords[0]):
                pieces.append(shapely.Point(coords[0]))
            else:
                pieces.append(shapely.simplify(shapely.LineString(coords), SIMPLIFY_M,
                                                 preserve_topology=False))
        return np.array(pieces, dtype=object)
    return ctx.cached(("corridor", drone_id), make)


def reached_by_any(ctx: CheckContext, target_id: str) -> bool:
    return any(visits(ctx, d, target_id) for d in ctx.drone_ids)


def coverage(ctx: CheckContext, target_id: str) -> float:
    """Covered fraction of the target in the window, 0..1."""
    def make() -> float:
        target = ctx.target(target_id)
        if not target.is_area:
            return 1.0 if reached_by_any(ctx, target_id) else 0.0
        x0, y0, x1, y1 = target.geometry.bounds
        swept = []
        for drone_id in ctx.drone_ids:
            lines = corridor_lines(ctx, drone_id)
            if not lines.size:
                continue
            radius = ctx.vehicle(drone_id).task_radius_m
            margin = radius + 1.0
            clipped = shapely.clip_by_rect(lines, x0 - margin, y0 - margin, x1 + margin,
                                           y1 + margin)
            clipped = clipped[~shapely.is_empty(clipped)]
            if clipped.size:
                swept.append(shapely.buffer(clipped, radius, quad_segs=_BUFFER_QUAD_SEGS))
        if not swept:
            return 0.0
        union = shapely.union_all(np.concatenate(swept))
        covered = shapely.intersection(target.geometry, union).area
        return float(min(max(covered / target.geometry.area, 0.0), 1.0))
    return ctx.cached(("coverage", target_id), make)


def _counted_targets(ctx: CheckContext) -> list[str]:
    return [t.id for t in ctx.scenario.world.targets if not t.is_charging_station]


TRACKING_WINDOW_S = 10.0
"""A reach of a moving target keeps it tracked this long (the reference's window)."""


def _tracked_now(ctx: CheckContext, target_id: str) -> bool:
    """Tracked at the window's end (MultiUAV-Plat's target_tracking progress)."""
    slack = TRACKING_WINDOW_S if ctx.target(target_id).is_moving else 0.0
    return any(v.end_s + slack >= ctx.t1_s - 1e-9
               for d in ctx.drone_ids for v in visits(ctx, d, target_id))


def task_progress(ctx: CheckContext) -> float:
    """Progress ratio of the scenario's task type over the window.

    Area families: floor(100 * mean coverage) / 100 (1.0 without targets); target_assignment:
    floor(100 * reached / count) / 100 (0 without targets); target_tracking: floor(100 *
    currently tracked / count) / 100, a moving target being tracked when some drone had it in
    range within TRACKING_WINDOW_S of the window's end and another target when a drone has it
    in range at the end (0 without targets); other task types: the fraction of targets reached
    (0 without targets).
    """
    ids = _counted_targets(ctx)
    if ctx.scenario.task_type in AREA_TASK_TYPES:
        if not ids:
            return 1.0
        mean = sum(coverage(ctx, t) for t in ids) / len(ids)
        return math.floor(100.0 * mean + 1e-9) / 100.0
    if not ids:
        return 0.0
    if ctx.scenario.task_type == "target_tracking":
        tracked = sum(_tracked_now(ctx, t) for t in ids)
        return (100 * tracked // len(ids)) / 100.0
    reached = sum(reached_by_any(ctx, t) for t in ids)
    if ctx.scenario.task_type == "target_assignment":
        return (100 * reached // len(ids)) / 100.0
    return reached / len(ids)


def task_done(ctx: CheckContext) -> bool:
    """Area families: every target covered >= DONE_COVERAGE (true without targets); others:
    every target reached (false without targets)."""
    ids = _counted_targets(ctx)
    if ctx.scenario.task_type in AREA_TASK_TYPES:
        return all(coverage(ctx, t) >= DONE_COVERAGE for t in ids)
    return bool(ids) and all(reached_by_any(ctx, t) for t in ids)
