"""Resilience (the resilience family): tasks whose hidden part schedules a vehicle failure or a
degraded link at a simulated time (benchmark.authoring.task_faults), checked on what the team still
achieves with the drones that remain.

The task text states the goal and, where it helps, a suggested split of the work; it never
names the fault. The agent has to notice it from telemetry and outcomes (a `failed` drone, a
drone returning home on a battery failsafe, commands that need retrying) and hand the lost
drone's share to the others. The oracle plan is written knowing the schedule: the drone that
will fail takes off and holds until the fault strikes (``until_fault``), and the healthy drones
do the whole job. Checks accept the work from any drone of the team.

Faults strike early in the task (FAULT_AFTER_S), before the failing drone could have finished
its share, so an agent that does not replan leaves that share undone.
"""

from __future__ import annotations

import math
import random
from collections.abc import Sequence
from typing import Any

from benchmark.authoring.template_files.loader import load_template
from benchmark.authoring.templates.base import (
    SessionView,
    TaskDraft,
    Template,
    TemplateUnfit,
    all_of,
    fmt_xy,
    leaf,
    pick,
    tour_length,
)
from benchmark.authoring.templates.common import FILES, spread_points
from benchmark.authoring.templates.common import diagonal_m as _diagonal_m
from benchmark.authoring.templates.common import names as _names
from benchmark.authoring.templates.common import target_xy as _xy
from emulator.scenario import VehicleSpec

__all__ = ["FAULT_AFTER_S", "LOSSY_LINK", "TEMPLATES"]

_CATEGORY = "resilience"
_FAMILY = ("resilience",)
FAULT_AFTER_S = (10, 30)  # the fault strikes this many simulated seconds into the task
HOLD_EXTRA_S = 30.0  # the failing drone's hold outlasts its fault by this much
# The degraded link of one drone: commands lost on the way up (MAVSDK sends them again), and
# latency with jitter both ways. Replies are not lost: a lost acknowledgement makes a command's
# fate depend on wall-clock retransmission timing, which would make a proof depend on load.
LOSSY_LINK = {"uplink": {"loss": 0.2}, "latency_ms": 60.0, "jitter_ms": 20.0}
SQUARE_M = 450.0  # the points of one task lie within a square of this side
_TRIES = 60

Point = tuple[float, float]
Node = dict[str, Any]


def _failure(drone: VehicleSpec, unit: str, rng: random.Random) -> tuple[dict[str, Any], int]:
    after = rng.randint(*FAULT_AFTER_S)
    return {"failures": [{"drone": drone.id, "after_s": after, "unit": unit}]}, after


def _hold(drone: VehicleSpec, alt: int, after_s: int) -> Node:
    return {"op": "until_fault", "drone": drone.id, "altitude_m": alt,
            "duration_s": after_s + HOLD_EXTRA_S}


def _points(view: SessionView, rng: random.Random, n: int, min_gap_m: float) -> list[Point]:
    return spread_points(view, rng, n, min_gap_m, SQUARE_M, _TRIES)


def _team(view: SessionView, rng: random.Random, lo: int, hi: int
          ) -> tuple[list[VehicleSpec], VehicleSpec, list[VehicleSpec]]:
    """A team of lo..hi drones, the one that will fail, and the others."""
    team = pick(rng, view.drones, rng.randint(lo, min(hi, len(view.drones))))
    failing = rng.choice(team)
    return team, failing, [d for d in team if d is not failing]


def _any_of(*checks: Node) -> Node:
    return {"logic": "or", "checks": list(checks)}


def _landed_at(drone_id: str, point: Point) -> Node:
    return leaf("drone_has_visited_position", drone_id=drone_id, x=point[0], y=point[1], z=0.0,
                tolerance=3.0)


def _land_ops(drone_id: str, points: Sequence[Point], alt: int) -> list[Node]:
    ops: list[Node] = []
    for x, y in points:
        ops += [{"op": "goto", "drone": drone_id, "x": x, "y": y, "z": alt},
                {"op": "land", "drone": drone_id}]
    return ops


# ------------------------------------------------------------------ a motor lost mid-search
def _search_motor(view: SessionView, rng: random.Random) -> TaskDraft:
    team, failing, healthy = _team(view, rng, 3, 4)
    (area,) = pick(rng, view.areas, 1)
    alt = view.cruise_altitude(rng)
    faults, after = _failure(failing, "motor", rng)
    radius = min(d.task_radius_m for d in healthy)
    sweep_m = area.geometry.area / (1.6 * radius) + area.geometry.length
    return TaskDraft(
        phrasings=[
            f"Search {area.name} around {_xy(area)} with {_names(team)}, flying at {alt} m: "
            f"at least 85 % of the area must be swept by the team's task radii.",
            f"Team search: {_names(team)} share the sweep of {area.name} (centred near "
            f"{_xy(area)}) at {alt} metres until 85 % or more of it is covered.",
            f"Cover no less than 85 % of {area.name} near {_xy(area)} using {_names(team)} at "
            f"an altitude of {alt} m.",
        ],
        checks=leaf("target_searched_area_percentage", target_id=area.id,
                    expected_percentage=0.85),
        oracle=[[_hold(failing, alt, after),
                 {"op": "sweep", "drones": [d.id for d in healthy], "target": area.id,
                  "altitude_m": alt}]],
        flight_m=_diagonal_m(view) + 1.2 * sweep_m / len(healthy),
        steps=6 + 2 * len(team), faults=faults,
    )


# ------------------------------------------------------------------ GPS lost on the way
def _reach_gps(view: SessionView, rng: random.Random) -> TaskDraft:
    team, failing, healthy = _team(view, rng, 2, 3)
    fixed = [t for t in view.points if t.kind == "fixed"]
    if len(fixed) < len(team) + 1:
        raise TemplateUnfit(f"needs {len(team) + 1} fixed targets")
    targets = pick(rng, fixed, len(team) + 1)
    alt = view.cruise_altitude(rng)
    faults, after = _failure(failing, "gps", rng)
    shares: list[tuple[VehicleSpec, list[Any]]] = [(failing, targets[:2])]
    shares += [(d, [t]) for d, t in zip(healthy, targets[2:], strict=True)]
    split = "; ".join(f"{d.name} takes {_names(ts)}" for d, ts in shares)
    listed = "; ".join(f"{t.name} at {_xy(t)}" for t in targets)
    return TaskDraft(
        phrasings=[
            f"Every one of these targets must be reached by a drone of {_names(team)}, flying "
            f"at {alt} m: {listed}. Suggested split: {split}.",
            f"Inspect {listed} with {_names(team)} at {alt} metres, so that each target is "
            f"flown over by some drone ({split}).",
            f"Target round for {_names(team)} at {alt} m: {split}. The task is done when all "
            f"of {_names(targets)} have been reached.",
        ],
        checks=all_of(*(leaf("target_is_reached", target_id=t.id) for t in targets)),
        oracle=[[_hold(failing, alt, after),
                 {"op": "visit_targets", "drones": [d.id for d in healthy],
                  "targets": [t.id for t in targets], "altitude_m": alt}]],
        flight_m=1.5 * _diagonal_m(view), steps=6 + 2 * len(targets), faults=faults,
    )


# ------------------------------------------------------------------ battery lost on patrol
def _patrol_battery(view: SessionView, rng: random.Random) -> TaskDraft:
    first, second = pick(rng, view.drones, 2)
    alt = rng.randint(15, 30)
    points = _points(view, rng, rng.randint(3, 4), 80.0)
    faults, after = _failure(first, "battery", rng)
    listed = ", ".join(fmt_xy(*p) for p in points)
    return TaskDraft(
        phrasings=[
            f"Patrol round at {alt} m: {first.name} flies over {listed} in this order, with "
            f"{second.name} as the team's second drone. Every point must be flown over at "
            f"{alt} m by {first.name} or {second.name}.",
            f"{first.name} and {second.name} together must pass over each of {listed} at "
            f"{alt} metres; {first.name} is to fly the round.",
            f"Fly the patrol points {listed} at an altitude of {alt} m, {first.name} on the "
            f"round and {second.name} standing by, so that each point is overflown by one of "
            f"the two.",
        ],
        checks=all_of(*(_any_of(*(leaf("drone_has_visited_position", drone_id=d.id, x=x, y=y,
                                       z=float(alt), tolerance=3.0)
                                  for d in (first, second)))
                        for x, y in points)),
        oracle=[[_hold(first, alt, after),
                 {"op": "path", "drone": second.id,
                  "points": [[x, y, alt] for x, y in points]}]],
        flight_m=_diagonal_m(view) + tour_length(points), steps=8, faults=faults,
    )


# ------------------------------------------------------------------ a motor lost in delivery
def _delivery_motor(view: SessionView, rng: random.Random) -> TaskDraft:
    first, second = pick(rng, view.drones, 2)
    alt = rng.randint(15, 30)
    pick_a, drop_a, pick_b, drop_b = _points(view, rng, 4, 80.0)
    faults, after = _failure(first, "motor", rng)
    parcels = ((first, pick_a, drop_a), (second, pick_b, drop_b))

    def delivered(p: Point, q: Point) -> Node:
        return _any_of(*(all_of(_landed_at(d.id, p), _landed_at(d.id, q))
                         for d in (first, second)))

    pa, qa, pb, qb = (fmt_xy(*p) for p in (pick_a, drop_a, pick_b, drop_b))
    return TaskDraft(
        phrasings=[
            f"Two parcels, flown at {alt} m: {first.name} lands at {pa} to pick one up and "
            f"then lands at {qa} to drop it; {second.name} does the same from {pb} to {qb}. "
            f"Each parcel must be carried by one drone from its pickup to its drop point.",
            f"Deliver both parcels with {first.name} and {second.name} at {alt} metres: one "
            f"from {pa} to {qa} (planned for {first.name}), one from {pb} to {qb} (planned "
            f"for {second.name}), landing at every stop.",
            f"Parcel runs at {alt} m: {pa} -> {qa} by {first.name} and {pb} -> {qb} by "
            f"{second.name}. A parcel counts when the same drone landed at its pickup and at "
            f"its drop point.",
        ],
        checks=all_of(*(delivered(p, q) for _, p, q in parcels)),
        oracle=[[_hold(first, alt, after),
                 *_land_ops(second.id, [pick_b, drop_b, pick_a, drop_a], alt)]],
        flight_m=_diagonal_m(view) + tour_length([pick_b, drop_b, pick_a, drop_a]),
        steps=14, faults=faults,
    )


# ------------------------------------------------------------------ a lossy link in delivery
def lossy_delivery(view: SessionView, rng: random.Random, values: dict[str, Any],
                   entities: dict[str, Any]) -> dict[str, Any]:
    """Hook of delivery_over_lossy_link.json: pickup and drop spots, their distance and the
    seed of the degraded link."""
    pickup, drop = _points(view, rng, 2, 150.0)
    return {"pickup": pickup, "drop": drop, "flight": math.dist(pickup, drop),
            "link_seed": rng.randrange(1, 2**31)}



TEMPLATES: tuple[Template, ...] = (
    Template("search_despite_motor_failure", _CATEGORY, "hard", _search_motor, drones=3,
             area_targets=1, families=_FAMILY),
    Template("reach_despite_gps_loss", _CATEGORY, "medium", _reach_gps, drones=2,
             point_targets=4, families=_FAMILY),
    Template("patrol_despite_battery_failure", _CATEGORY, "medium", _patrol_battery,
             drones=2, families=_FAMILY),
    Template("delivery_despite_motor_failure", _CATEGORY, "hard", _delivery_motor, drones=2,
             families=_FAMILY),
    load_template(FILES / "delivery_over_lossy_link.json"),
)
