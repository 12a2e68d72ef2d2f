"""Target checks over the window: reaching, tracking, coverage and task progress."""

from __future__ import annotations

import numpy as np

from benchmark.scoring.validators.context import CheckContext
from benchmark.scoring.validators.coverage import (
    TRACKING_WINDOW_S,
    coverage,
    task_done,
    task_progress,
)
from benchmark.scoring.validators.endpoint import (
    Endpoint,
    Outcome,
    Params,
    Runner,
    Validator,
    target_kind,
)
from benchmark.scoring.validators.geometry import point_segment_distance
from benchmark.scoring.validators.params import REQUIRED, ParamSpec, entity, integer, number
from benchmark.scoring.validators.reach import target_rows, visits

__all__ = ["TARGET_ENDPOINTS", "TRACKING_WINDOW_S", "tracking_periods"]

_RATIO_EPS = 1e-9


def _reaching_drones(ctx: CheckContext, target_id: str) -> int:
    return sum(bool(visits(ctx, d, target_id)) for d in ctx.drone_ids)


def _target_is_reached(ctx: CheckContext, p: Params) -> Outcome:
    count = _reaching_drones(ctx, p["target_id"])
    return Outcome(count > 0, count)


def _target_is_reached_by_drone(ctx: CheckContext, p: Params) -> Outcome:
    count = len(visits(ctx, p["drone_id"], p["target_id"]))
    return Outcome(count > 0, count)


def _target_reached_drone_number(ctx: CheckContext, p: Params) -> Outcome:
    count = _reaching_drones(ctx, p["target_id"])
    expected = p["expected_count"]
    return Outcome(count >= expected if expected is not None else count > 0, count)


def tracking_periods(ctx: CheckContext, target_id: str, drone_id: str | None
                     ) -> list[tuple[float, float]]:
    """MultiUAV-Plat's tracking periods of a moving target: every instant a drone (the given
    one, or any) has it in range opens or extends a period to TRACKING_WINDOW_S after it;
    periods that meet are one."""
    drones = ctx.drone_ids if drone_id is None else (drone_id,)
    spans = sorted((v.start_s, v.end_s + TRACKING_WINDOW_S)
                   for d in drones for v in visits(ctx, d, target_id))
    periods: list[tuple[float, float]] = []
    for start, end in spans:
        if periods and start <= periods[-1][1]:
            periods[-1] = (periods[-1][0], max(periods[-1][1], end))
        else:
            periods.append((start, end))
    return periods


def _moving_target_tracked(ctx: CheckContext, p: Params) -> Outcome:
    periods = tracking_periods(ctx, p["target_id"], p["drone_id"])
    longest = max((b - a for a, b in periods), default=0.0)
    return Outcome(bool(periods) and longest + 1e-9 >= p["min_duration"], round(longest, 3))


def _moving_target_reached_in_zone(ctx: CheckContext, p: Params) -> Outcome:
    """In range of the drone while the target was within `radius` of (x, y)."""
    rows = target_rows(ctx, p["target_id"])
    count = 0
    for visit in visits(ctx, p["drone_id"], p["target_id"]):
        if rows is None or rows.shape[0] == 0:
            break
        inner = rows[(rows[:, 0] > visit.start_s) & (rows[:, 0] < visit.end_s), 0]
        times = np.concatenate(([visit.start_s], inner, [visit.end_s]))
        xy = np.column_stack([np.interp(times, rows[:, 0], rows[:, c]) for c in (1, 2)])
        a, b = xy[:-1], xy[1:]
        d = point_segment_distance(a, b, np.array([p["x"], p["y"]]))
        count += bool(np.any(d <= p["radius"] + 1e-9))
    return Outcome(count > 0, count)


def _target_is_fully_searched(ctx: CheckContext, p: Params) -> Outcome:
    ratio = coverage(ctx, p["target_id"])
    return Outcome(ratio + _RATIO_EPS >= p["coverage_threshold"], round(ratio, 4))


def _target_searched_area_percentage(ctx: CheckContext, p: Params) -> Outcome:
    ratio = coverage(ctx, p["target_id"])
    return Outcome(ratio + _RATIO_EPS >= p["expected_percentage"], round(ratio, 4))


def _task_progress(ctx: CheckContext, p: Params) -> Outcome:
    progress = task_progress(ctx)
    return Outcome(progress + _RATIO_EPS >= p["expected_progress"], round(progress, 4))


def _task_done(ctx: CheckContext, p: Params) -> Outcome:
    return Outcome(task_done(ctx), round(task_progress(ctx), 4))


_TARGET = entity("target_id", "target")


def _ratio(name: str, default: object) -> ParamSpec:
    return number(name, default, minimum=0.0, maximum=1.0)


def _targets(name: str, description: str, run: Runner, *params: ParamSpec,
             validate: Validator | None = None) -> Endpoint:
    return Endpoint(name, "targets", description, params, run, validate)


TARGET_ENDPOINTS: tuple[Endpoint, ...] = (
    _targets("target_is_reached", "some drone reached the target; value: number of drones",
             _target_is_reached, _TARGET),
    _targets("target_is_reached_by_drone", "the drone reached the target; value: visits",
             _target_is_reached_by_drone, _TARGET, entity("drone_id", "drone")),
    _targets("target_reached_drone_number",
             "distinct drones reaching the target >= expected_count (> 0 when absent)",
             _target_reached_drone_number, _TARGET,
             integer("expected_count", None, minimum=0)),
    _targets("moving_target_tracked",
             "some tracking period of the target (by the given drone, or any) lasts >= "
             "min_duration seconds; a period runs from a reach to 10 s after the last reach "
             "that follows within 10 s; value: longest period",
             _moving_target_tracked, _TARGET, entity("drone_id", "drone", None),
             number("min_duration", 0.0, minimum=0.0),
             validate=target_kind("target_id", "moving")),
    _targets("moving_target_reached_in_zone",
             "the drone reached the moving target while the target was within radius of "
             "(x, y); value: such visits",
             _moving_target_reached_in_zone, _TARGET, entity("drone_id", "drone"),
             number("x", REQUIRED), number("y", REQUIRED), number("radius", REQUIRED,
                                                                   minimum=0.0),
             validate=target_kind("target_id", "moving")),
    _targets("target_is_fully_searched", "coverage ratio >= coverage_threshold",
             _target_is_fully_searched, _TARGET, _ratio("coverage_threshold", 0.99)),
    _targets("target_searched_area_percentage", "coverage ratio >= expected_percentage",
             _target_searched_area_percentage, _TARGET, _ratio("expected_percentage", REQUIRED)),
    _targets("task_progress", "task progress ratio >= expected_progress", _task_progress,
             _ratio("expected_progress", REQUIRED)),
    _targets("task_done", "the session's task is completed in the window; value: progress",
             _task_done),
)
