"""Search: photos at points, inspections of named targets, watching from a hover, and the
coverage of area targets by one drone, a team or the whole fleet."""

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
from benchmark.authoring.templates.common import FILES
from benchmark.authoring.templates.common import diagonal_m as _diagonal_m
from benchmark.authoring.templates.common import inspectable as _inspectable
from benchmark.authoring.templates.common import names as _names
from benchmark.authoring.templates.common import target_xy as _xy
from emulator.scenario import VehicleSpec
from emulator.world import Target

__all__ = ["TEMPLATES"]

_AREA_FAMILIES = ("area_search", "area_assignment_and_patrol")


# ------------------------------------------------------------------ helpers
def _nearest_first(start: Sequence[float], targets: list[Target]) -> list[Target]:
    return sorted(targets, key=lambda t: math.dist(start[:2], t.position_m[:2]))


def _sweep_m(area: Target, task_radius_m: float) -> float:
    """Rough length of a lawnmower over the area, lanes 1.6 task radii apart, turns included."""
    return area.geometry.area / (1.6 * task_radius_m) + area.geometry.length


def _spread_points(view: SessionView, rng: random.Random, count: int,
                   min_gap_m: float = 50.0) -> list[tuple[float, float]]:
    points: list[tuple[float, float]] = []
    for _ in range(60):
        p = view.free_point(rng)
        if all(math.dist(p, q) >= min_gap_m for q in points):
            points.append(p)
            if len(points) == count:
                return points
    raise TemplateUnfit(f"no {count} free points {min_gap_m:g} m apart")


# ------------------------------------------------------------------ photos and hovering
def _inspect_two_targets(view: SessionView, rng: random.Random) -> TaskDraft:
    (d,) = pick(rng, view.drones, 1)
    first, second = _nearest_first(d.position_m, pick(rng, _inspectable(view, 2), 2))
    alt = view.cruise_altitude(rng)
    ops = []
    for t in (first, second):
        ops += [{"op": "reach", "drone": d.id, "target": t.id, "altitude_m": alt},
                {"op": "photo", "drone": d.id}]
    return TaskDraft(
        phrasings=[
            f"With {d.name}, inspect two targets: {first.name} at {_xy(first)} and "
            f"{second.name} at {_xy(second)}. Fly over each one and take a photo of it from "
            f"above its centre.",
            f"{d.name} has to photograph both {first.name}, at {_xy(first)}, and {second.name}, "
            f"at {_xy(second)}: reach each target and take a picture while hovering over it.",
            f"Visit {first.name} near {_xy(first)} and then {second.name} near {_xy(second)} "
            f"using {d.name}, capturing one overhead image of each target.",
        ],
        checks=all_of(
            leaf("target_is_reached_by_drone", target_id=first.id, drone_id=d.id),
            leaf("target_is_reached_by_drone", target_id=second.id, drone_id=d.id),
            leaf("target_in_photo_taken_by_drone", drone_id=d.id, target_id=first.id),
            leaf("target_in_photo_taken_by_drone", drone_id=d.id, target_id=second.id),
        ),
        oracle=[ops],
        flight_m=_diagonal_m(view) + math.dist(first.position_m[:2], second.position_m[:2]),
        steps=5,
    )


def hold_check(view: SessionView, rng: random.Random, values: dict[str, Any],
               entities: dict[str, Any]) -> dict[str, Any]:
    """Hook of observe_and_hover.json: the hover the check asks for, a second short of the
    one the text asks for."""
    return {"min_hold": values["hold_s"] - 1}


def _photo_series(view: SessionView, rng: random.Random) -> TaskDraft:
    (d,) = pick(rng, view.drones, 1)
    alt = rng.randint(15, 25)
    points = _spread_points(view, rng, 3)
    listed = ", ".join(fmt_xy(x, y) for x, y in points[:2]) + " and " + fmt_xy(*points[2])
    ops = []
    for x, y in points:
        ops += [{"op": "goto", "drone": d.id, "x": x, "y": y, "z": alt},
                {"op": "photo", "drone": d.id}]
    return TaskDraft(
        phrasings=[
            f"Document three spots with {d.name}: fly at {alt} m to {listed} in turn and take a "
            f"photo at each of them.",
            f"{d.name} must take three pictures, one at each of {listed}, flying at an altitude "
            f"of {alt} metres.",
            f"At {alt} m, send {d.name} over {listed} and snap a photo at every one of these "
            f"three points.",
        ],
        checks=all_of(
            *(leaf("drone_has_visited_position", drone_id=d.id, x=x, y=y, z=float(alt),
                   tolerance=3.0) for x, y in points),
            leaf("drone_has_taken_photo", drone_id=d.id, min_count=3),
        ),
        oracle=[ops],
        flight_m=_diagonal_m(view) + tour_length(points),
        steps=7,
    )


# ------------------------------------------------------------------ area coverage
def sweep_length(view: SessionView, rng: random.Random, values: dict[str, Any],
                 entities: dict[str, Any]) -> dict[str, Any]:
    """Hook of area_sweep.json: the rough length of a sweep of the area (budget)."""
    return {"flight": _sweep_m(entities["area_1"], entities["drone_1"].task_radius_m)}



def _team_area_sweep(view: SessionView, rng: random.Random) -> TaskDraft:
    team = pick(rng, view.drones, rng.randint(2, min(3, len(view.drones))))
    (t,) = pick(rng, view.areas, 1)
    alt = rng.randint(18, 30)
    radius = min(d.task_radius_m for d in team)
    return TaskDraft(
        phrasings=[
            f"Search {t.name} (centred near {_xy(t)}) as a team with {_names(team)}. Each drone "
            f"takes off to {alt} m and searches at that altitude; every one of them must fly "
            f"over the area, and together they must cover at least 95 % of it.",
            f"{_names(team)} should share the sweep of {t.name} around {_xy(t)}: launch each to "
            f"exactly {alt} metres, let every drone search part of the area, and reach 95 % "
            f"coverage or more.",
            f"Team search: {_names(team)} climb to {alt} m and jointly cover {t.name} near "
            f"{_xy(t)} until at least 95 % of it is searched, each drone taking its share over "
            f"the area.",
        ],
        checks=all_of(
            *(leaf("drone_has_taken_off", drone_id=d.id, min_altitude=float(alt),
                   max_altitude=float(alt), tolerance=1.5) for d in team),
            *(leaf("target_is_reached_by_drone", target_id=t.id, drone_id=d.id) for d in team),
            leaf("target_is_fully_searched", target_id=t.id, coverage_threshold=0.95),
        ),
        oracle=[[{"op": "takeoff", "drone": d.id, "altitude_m": alt} for d in team],
                [{"op": "sweep", "drones": [d.id for d in team], "target": t.id,
                  "altitude_m": alt}]],
        flight_m=_diagonal_m(view) + 1.2 * _sweep_m(t, radius) / len(team),
        steps=3 * len(team),
    )


def _two_area_search(view: SessionView, rng: random.Random) -> TaskDraft:
    first, second = pick(rng, view.areas, 2)
    team = pick(rng, view.drones, rng.randint(2, min(4, len(view.drones))))
    radius = min(d.task_radius_m for d in team)
    # The larger area gets the larger half of the team.
    big_first = first.geometry.area >= second.geometry.area
    cut = (len(team) + 1) // 2 if big_first else len(team) // 2
    groups = ((first, team[:cut]), (second, team[cut:]))
    alt = view.cruise_altitude(rng)
    return TaskDraft(
        phrasings=[
            f"Search two areas completely: {first.name} (centred near {_xy(first)}) and "
            f"{second.name} (centred near {_xy(second)}). Use any drones you like; each area "
            f"must end up at least 95 % covered.",
            f"Both {first.name} around {_xy(first)} and {second.name} around {_xy(second)} "
            f"need a full search (95 % coverage or better for each). Any of the drones may "
            f"take part.",
            f"Cover at least 95 % of {first.name} near {_xy(first)} and at least 95 % of "
            f"{second.name} near {_xy(second)}, with as many drones of the fleet as you choose.",
        ],
        checks=all_of(
            leaf("target_is_reached", target_id=first.id),
            leaf("target_is_reached", target_id=second.id),
            leaf("target_is_fully_searched", target_id=first.id, coverage_threshold=0.95),
            leaf("target_is_fully_searched", target_id=second.id, coverage_threshold=0.95),
        ),
        oracle=[[{"op": "sweep", "drones": [d.id for d in group], "target": t.id,
                  "altitude_m": alt} for t, group in groups]],
        flight_m=_diagonal_m(view) + max(1.2 * _sweep_m(t, radius) / len(group)
                                         for t, group in groups),
        steps=3 * len(team),
    )


def _share_areas(view: SessionView) -> list[tuple[Target, list[VehicleSpec]]]:
    """Each area with the drones that sweep it: every area gets a drone, spare drones go to
    the areas with the most sweeping per drone; with fewer drones than areas, drones take
    several areas (single-drone sweeps, flown one after the other)."""
    drones, areas = view.drones, view.areas
    if len(drones) < len(areas):
        return [(a, [drones[k % len(drones)]]) for k, a in enumerate(areas)]
    counts = [1] * len(areas)
    for _ in range(len(drones) - len(areas)):
        k = max(range(len(areas)), key=lambda i: areas[i].geometry.area / counts[i])
        counts[k] += 1
    shares, start = [], 0
    for area, count in zip(areas, counts, strict=True):
        shares.append((area, drones[start:start + count]))
        start += count
    return shares


def _search_progress(view: SessionView, rng: random.Random) -> TaskDraft:
    alt = view.cruise_altitude(rng)
    shares = _share_areas(view)
    radius = min(d.task_radius_m for d in view.drones)
    per_drone: dict[str, float] = {}
    for area, group in shares:
        for d in group:
            leg = _diagonal_m(view) + 1.2 * _sweep_m(area, radius) / len(group)
            per_drone[d.id] = per_drone.get(d.id, 0.0) + leg
    listed = "; ".join(f"{a.name} near {_xy(a)}" for a in view.areas)
    return TaskDraft(
        phrasings=[
            f"Carry out this session's area search with the whole fleet. The areas to search are: "
            f"{listed}. Share them out among the drones and keep searching until the overall "
            f"search progress (the mean coverage of the areas) is at least 90 %.",
            f"All drones take part: search every area of the session ({listed}) until at least "
            f"90 % overall search progress is reached.",
            f"Bring the session's area search to 90 % progress or more, dividing these areas "
            f"among all the drones: {listed}.",
        ],
        checks=all_of(leaf("task_progress", expected_progress=0.9)),
        oracle=[[{"op": "sweep", "drones": [d.id for d in group], "target": area.id,
                  "altitude_m": alt} for area, group in shares]],
        flight_m=max(per_drone.values()),
        steps=3 * sum(len(group) for _, group in shares),
    )


def team_sweep_length(view: SessionView, rng: random.Random, values: dict[str, Any],
                      entities: dict[str, Any]) -> dict[str, Any]:
    """Hook of sweep_with_photos.json: each drone's share of the sweep (budget)."""
    team = [entities[f"drone_{k}"] for k in (1, 2, 3)]
    radius = min(d.task_radius_m for d in team)
    return {"flight": 1.2 * _sweep_m(entities["area_1"], radius) / len(team)}



TEMPLATES = (
    load_template(FILES / "photo_at_point.json"),
    load_template(FILES / "inspect_target.json"),
    Template("inspect_two_targets", "search", "hard", _inspect_two_targets),
    load_template(FILES / "observe_and_hover.json"),
    Template("photo_series", "search", "medium", _photo_series),
    load_template(FILES / "area_sweep.json"),
    Template("team_area_sweep", "search", "hard", _team_area_sweep, drones=2, area_targets=1,
             families=_AREA_FAMILIES),
    Template("two_area_search", "search", "hard", _two_area_search, drones=2, area_targets=2,
             families=_AREA_FAMILIES),
    Template("search_progress", "search", "hard", _search_progress, area_targets=1,
             families=_AREA_FAMILIES),
    load_template(FILES / "sweep_with_photos.json"),
)
