"""MultiUAV-Plat's tracking history of moving targets (entities.md sections 3.2, 3.3 and 6.4):
a moving target's `tracking_status` (`never_tracked`, `tracked`, `stale`) and `last_tracked_at`
on its record, and the session's serialised `history.moving_target_tracking`.

The reference records a track event each time a command ends with a drone within its task
radius of a moving target, and each event opens or extends a tracking period to
TRACKING_WINDOW_S after it. Here a drone tracks a target for as long as it both reaches it
(within its task radius, as the validators measure reaches) and perceives it (within its
sensor's radius): every such stretch of the flight in the current task's window is one track
event, starting where it starts, its period lasting until TRACKING_WINDOW_S after the stretch
ends. So the history holds only what the drones' own sensors saw (where the task radius is
the smaller, as in every generated and reference session, the periods are exactly those
`moving_target_tracked` measures), and an agent, which gets records only of targets its
drones perceive, learns nothing more. Times are simulated seconds.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from benchmark.scoring.validators import CheckContext
from benchmark.scoring.validators.coverage import TRACKING_WINDOW_S
from benchmark.scoring.validators.geometry import Footprint
from benchmark.scoring.validators.reach import Visit, flight_path, footprint, target_rows, visits

__all__ = ["PERIODS_KEPT", "RECENT_PERIODS", "moving_target_tracking", "perceived_visits",
           "tracking_entry", "tracking_fields"]

PERIODS_KEPT = 10
"""Tracking periods the reference retains per target and per drone."""
RECENT_PERIODS = 5
"""Periods in a serialised entry (`recent_periods`)."""


def perceived_visits(ctx: CheckContext, drone_id: str, target_id: str) -> tuple[Visit, ...]:
    """The stretches of the drone's flight in the window with the target within its task
    radius and its sensor's radius, in time order."""
    spec = ctx.vehicle(drone_id)
    if spec.perceived_radius_m >= spec.task_radius_m:
        return visits(ctx, drone_id, target_id)

    def make() -> tuple[Visit, ...]:
        path = flight_path(ctx, drone_id)
        shape = footprint(ctx, target_id)
        rows = target_rows(ctx, target_id)
        if rows is not None:
            path = path.relative_to(rows)
            shape = Footprint((0.0, 0.0), shape.bound_radius_m, shape.disc_radius_m, None,
                              None)
        mask = path.in_range(shape, spec.perceived_radius_m)
        return tuple(Visit(float(path.t0[f]), float(path.t1[e]))
                     for f, e in path.chains(mask))
    return ctx.cached(("perceived-visits", drone_id, target_id), make)


@dataclass
class _Period:
    start_s: float
    end_s: float
    last_update_s: float
    events: int = 0
    tracked_by: list[str] = field(default_factory=list)
    last_by: str = ""

    def add(self, drone: str, visit: Visit) -> None:
        self.end_s = max(self.end_s, visit.end_s + TRACKING_WINDOW_S)
        if visit.end_s >= self.last_update_s:
            self.last_update_s, self.last_by = visit.end_s, drone
        self.events += 1
        if drone not in self.tracked_by:
            self.tracked_by.append(drone)

    def to_json(self, with_drones: bool) -> dict[str, Any]:
        out: dict[str, Any] = {"start_at": round(self.start_s, 3),
                               "end_at": round(self.end_s, 3),
                               "last_update_at": round(self.last_update_s, 3),
                               "event_count": self.events}
        if with_drones:
            out.update(last_tracked_by=self.last_by, tracked_by=list(self.tracked_by))
        return out


def _periods(events: Sequence[tuple[Visit, str]]) -> list[_Period]:
    """Events in start order merged into periods: an event after a period's end opens the
    next one (the reference's rule)."""
    periods: list[_Period] = []
    for visit, drone in sorted(events, key=lambda e: (e[0].start_s, e[0].end_s, e[1])):
        if not periods or visit.start_s > periods[-1].end_s:
            periods.append(_Period(visit.start_s, visit.start_s, visit.start_s))
        periods[-1].add(drone, visit)
    return periods[-PERIODS_KEPT:]


def _events(ctx: CheckContext, target_id: str) -> list[tuple[Visit, str]]:
    return [(v, d) for d in ctx.drone_ids for v in perceived_visits(ctx, d, target_id)]


def _status(last_s: float | None, now_s: float) -> str:
    if last_s is None:
        return "never_tracked"
    return "tracked" if now_s - last_s <= TRACKING_WINDOW_S + 1e-9 else "stale"


def tracking_fields(ctx: CheckContext, target_id: str) -> dict[str, Any]:
    """`tracking_status` and `last_tracked_at` of a moving target's record."""
    ends = [v.end_s for v, _ in _events(ctx, target_id)]
    last = max(ends) if ends else None
    return {"tracking_status": _status(last, ctx.t1_s),
            "last_tracked_at": None if last is None else round(last, 3)}


def tracking_entry(events: Sequence[tuple[Visit, str]], now_s: float) -> dict[str, Any]:
    """One target's serialised tracking entry from its track events (a stretch of flight in
    reach and sight, and the drone), at simulated time now_s; `events` is not empty."""
    periods = _periods(events)
    last_visit, last_by = max(events, key=lambda e: (e[0].end_s, e[0].start_s))
    status = _status(last_visit.end_s, now_s)
    by_drone: dict[str, dict[str, Any]] = {}
    for drone in dict.fromkeys(d for _, d in sorted(events, key=lambda e: e[0].start_s)):
        mine = [(v, d) for v, d in events if d == drone]
        by_drone[drone] = {
            "first_tracked_at": round(min(v.start_s for v, _ in mine), 3),
            "last_tracked_at": round(max(v.end_s for v, _ in mine), 3),
            "total_track_events": len(mine),
            "recent_periods": [p.to_json(False) for p in _periods(mine)[-RECENT_PERIODS:]]}
    return {"tracking_status": status,
            "first_tracked_at": round(min(v.start_s for v, _ in events), 3),
            "last_tracked_at": round(last_visit.end_s, 3), "last_tracked_by": last_by,
            "tracked_by": list(by_drone), "total_track_events": len(events),
            "active_period_start": round(periods[-1].start_s, 3)
            if status == "tracked" else None,
            "recent_periods": [p.to_json(True) for p in periods[-RECENT_PERIODS:]],
            "by_drone": by_drone}


def moving_target_tracking(ctx: CheckContext) -> dict[str, dict[str, Any]]:
    """The serialised `history.moving_target_tracking`: an entry per moving target tracked in
    the window."""
    out: dict[str, dict[str, Any]] = {}
    for target in ctx.scenario.world.targets:
        if not target.is_moving:
            continue
        events = _events(ctx, target.id)
        if events:
            out[target.id] = tracking_entry(events, ctx.t1_s)
    return out
