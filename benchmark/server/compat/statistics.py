"""MultiUAV-Plat's session `statistics` and `task_progress` blocks (entities.md section 6.3),
measured on the emulator's ground truth of the current task's window (since the task started,
until now) with the validators' own geometry: reaches are visits within a drone's task radius,
coverage is the exact swept area, progress is what `/check/task_progress` evaluates. For
operators and admins only; an agent gets `agent_progress`, which holds nothing a check
decides."""

from __future__ import annotations

from typing import Any

import numpy as np

from benchmark.scoring.validators import CheckContext
from benchmark.scoring.validators.coverage import (
    AREA_TASK_TYPES,
    coverage,
    task_done,
    task_progress,
)
from benchmark.scoring.validators.reach import flight_path, visits
from benchmark.server.compat.tracking import tracking_fields
from benchmark.server.hub import LiveSession

__all__ = ["FULLY_COVERED", "agent_progress", "check_context", "reach_history",
           "statistics_block", "task_progress_block"]

FULLY_COVERED = 0.999
"""A target counts as fully covered from this coverage ratio on (the reference's 99.9 %)."""
RECENT_REACHES = 5
REFERENCE_TASK_TYPES = frozenset({*AREA_TASK_TYPES, "target_assignment", "target_tracking"})
"""Task types the reference measures progress of; for the others it answers 0, not done."""
UNTRACKED = "No progress tracking for this task type"


def check_context(live: LiveSession) -> CheckContext:
    """The ground truth of the current task's window, as the hidden checks read it."""
    return CheckContext(live.swarm.recorder, live.session.scenario, live.task_start_s,
                        live.services.clock_s())


def _reach_starts(ctx: CheckContext) -> dict[str, dict[str, list[float]]]:
    """Start times (simulated s) of every drone's visits to every target, non-empty only."""
    def make() -> dict[str, dict[str, list[float]]]:
        out: dict[str, dict[str, list[float]]] = {}
        for drone in ctx.drone_ids:
            for target in ctx.scenario.world.targets:
                starts = [round(v.start_s, 3) for v in visits(ctx, drone, target.id)]
                if starts:
                    out.setdefault(drone, {})[target.id] = starts
        return out
    return ctx.cached(("compat-reaches",), make)


def _reach_summary(ctx: CheckContext) -> dict[str, int]:
    reaches = _reach_starts(ctx)
    targets = {t for by_target in reaches.values() for t in by_target}
    return {"total_reaches": sum(len(v) for d in reaches.values() for v in d.values()),
            "drones_with_reaches": len(reaches), "unique_targets_reached": len(targets)}


def _coverage_by_target(ctx: CheckContext) -> dict[str, dict[str, Any]]:
    """Coverage entries as the reference keeps them: every area target, and point-type
    targets once reached (then 100 %)."""
    reached = {t for by_target in _reach_starts(ctx).values() for t in by_target}
    out: dict[str, dict[str, Any]] = {}
    for target in ctx.scenario.world.targets:
        if not target.is_area and target.id not in reached:
            continue
        ratio = coverage(ctx, target.id) if target.is_area else 1.0
        area = float(target.geometry.area) if target.is_area else 0.0
        out[target.id] = {"area_type": target.kind if target.is_area else "point",
                          "total_area": round(area, 2), "covered_area": round(area * ratio, 2),
                          "coverage_percentage": round(100.0 * ratio, 2)}
    return out


def _coverage_summary(ctx: CheckContext) -> dict[str, Any]:
    entries = _coverage_by_target(ctx)
    percentages = [e["coverage_percentage"] for e in entries.values()]
    return {"total_targets_tracked": len(entries),
            "average_coverage": round(sum(percentages) / len(percentages), 2)
            if percentages else 0.0,
            "fully_covered_targets": sum(p >= 100.0 * FULLY_COVERED for p in percentages)}


def task_progress_block(live: LiveSession, ctx: CheckContext | None = None) -> dict[str, Any]:
    """The reference's `task_progress` object for the current task's window."""
    ctx = ctx or check_context(live)
    task_type = live.session.task_type
    counted = [t for t in ctx.scenario.world.targets if not t.is_charging_station]
    reached = {t for by_target in _reach_starts(ctx).values() for t in by_target}
    details: dict[str, Any] = {
        "total_targets": len(counted),
        "visited_targets": [t.id for t in counted if t.id in reached],
        "unvisited_targets": [t.id for t in counted if t.id not in reached],
        "tracked_targets": [t.id for t in counted if t.motion is not None
                            and tracking_fields(ctx, t.id)["tracking_status"] == "tracked"]}
    if task_type in AREA_TASK_TYPES:
        mean = (sum(coverage(ctx, t.id) for t in counted) / len(counted)) if counted else 1.0
        details["average_coverage"] = round(100.0 * mean, 2)
    else:
        details["reached_targets"] = len(details["visited_targets"])
    if task_type in REFERENCE_TASK_TYPES:
        progress, done = int(100.0 * task_progress(ctx) + 1e-6), task_done(ctx)
        message = "Task Finished" if done else "Task to be Done"
    else:  # the reference measures no progress for other task types
        progress, done, message = 0, False, UNTRACKED
    return {"task_type": task_type, "progress_percentage": progress,
            "is_completed": done, "status_message": message, "details": details,
            "target_reach_summary": _reach_summary(ctx),
            "area_coverage_summary": _coverage_summary(ctx),
            "window_s": [round(ctx.t0_s, 3), round(ctx.t1_s, 3)]}


def _flown(ctx: CheckContext) -> tuple[float, float]:
    """(horizontal metres flown, airborne seconds) of every drone in the window."""
    distance_m = airborne_s = 0.0
    for drone in ctx.drone_ids:
        track = ctx.window(drone)
        if track.size > 1:
            step = np.diff(track.xy_m, axis=0)[track.joined]
            distance_m += float(np.hypot(step[:, 0], step[:, 1]).sum())
        path = flight_path(ctx, drone)
        airborne_s += float((path.t1 - path.t0).sum())
    return distance_m, airborne_s


def statistics_block(live: LiveSession) -> dict[str, Any]:
    """The reference's session `statistics` for the current task's window: counts of the whole
    map (so never for an agent), the agent's tool calls as its commands, flown distance and
    airborne time from the ground truth, reaches and progress."""
    ctx = check_context(live)
    data = live.session.data
    reach = _reach_summary(ctx)
    distance_m, airborne_s = _flown(ctx)
    calls = live.tools.tool_calls
    environment = data.get("environment")
    return {"drone_count": len(live.session.scenario.vehicles),
            "target_count": len(ctx.scenario.world.targets),
            "obstacle_count": len(ctx.scenario.world.obstacles),
            "task_count": len(live.session.tasks),
            "environment_id": environment.get("id") if isinstance(environment, dict) else None,
            "total_commands_executed": calls, "total_flight_time": round(airborne_s, 2),
            "total_distance_traveled": round(distance_m, 2),
            "total_target_reaches": reach["total_reaches"],
            "drones_with_target_reaches": reach["drones_with_reaches"],
            "unique_targets_reached": reach["unique_targets_reached"],
            "session_time": round(live.services.clock_s(), 3), "command_history_size": calls,
            "target_reach_log_size": reach["total_reaches"],
            "task_progress": task_progress_block(live, ctx)}


def reach_history(live: LiveSession) -> dict[str, Any]:
    """The reference's serialised `history.target_reaches` and `history.area_coverage` for the
    current task's window (times in simulated seconds)."""
    ctx = check_context(live)
    reaches = _reach_starts(ctx)
    by_drone = {drone: {target: {"count": len(times), "first_reached_at": times[0],
                                 "last_reached_at": times[-1],
                                 "recent_reached_at": times[-RECENT_REACHES:]}
                        for target, times in by_target.items()}
                for drone, by_target in reaches.items()}
    by_target: dict[str, dict[str, Any]] = {}
    for drone, targets in reaches.items():
        for target, times in targets.items():
            entry = by_target.setdefault(target, {"times": [], "reached_by": []})
            entry["times"].extend(times)
            entry["reached_by"].append(drone)
    serial = {target: {"total_reaches": len(e["times"]), "first_reached_at": min(e["times"]),
                       "last_reached_at": max(e["times"]), "reached_by": e["reached_by"],
                       "recent_reached_at": sorted(e["times"])[-RECENT_REACHES:],
                       "unique_drones": len(e["reached_by"])}
              for target, e in by_target.items()}
    return {"target_reaches": {"by_drone": by_drone, "by_target": serial},
            "area_coverage": _coverage_by_target(ctx)}


def agent_progress(live: LiveSession) -> dict[str, Any]:
    """Task progress for an agent: the reference's keys, but what the hidden checks decide
    (progress, completion, reaches, coverage) is null; details are the agent's own budget."""
    budget = live.task.budget
    untracked = live.session.task_type not in REFERENCE_TASK_TYPES
    return {"task_type": live.session.task_type,
            "progress_percentage": 0 if untracked else None,
            "is_completed": False if untracked else None,
            "status_message": UNTRACKED if untracked else
            "progress is judged by hidden checks after the task ends; agents do not see it",
            "details": {"task_id": live.task.id, "tool_calls": live.tools.tool_calls,
                        "tool_call_budget": None if budget is None else budget.tool_calls,
                        "sim_time_s": round(live.tools.sim_elapsed_s, 3),
                        "sim_time_budget_s": None if budget is None else budget.sim_time_s,
                        "finished": live.tools.finished},
            "target_reach_summary": None, "area_coverage_summary": None}
