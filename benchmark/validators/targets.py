"""Target checks over the window: reaching, tracking, coverage and task progress."""

from __future__ import annotations

from benchmark.validators.context import CheckContext
from benchmark.validators.coverage import coverage, task_done, task_progress
from benchmark.validators.endpoint import Endpoint, Outcome, Params, Runner, Validator, target_kind
from benchmark.validators.params import REQUIRED, ParamSpec, entity, integer, number
from benchmark.validators.reach import visits

__all__ = ["TARGET_ENDPOINTS"]

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


def _moving_target_tracked(ctx: CheckContext, p: Params) -> Outcome:
    drones = ctx.drone_ids if p["drone_id"] is None else (p["drone_id"],)
    durations = [v.duration_s for d in drones for v in visits(ctx, d, p["target_id"])]
    longest = max(durations, default=0.0)
    return Outcome(bool(durations) and longest >= p["min_duration"], round(longest, 3))


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
             "a drone (or the given one) stayed in range for >= min_duration seconds; "
             "value: longest period",
             _moving_target_tracked, _TARGET, entity("drone_id", "drone", None),
             number("min_duration", 0.0, minimum=0.0),
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
