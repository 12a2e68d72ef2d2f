"""Multi-drone coordination: formations, meeting points, launching the fleet, parallel straight
sweeps, and several drones checking the same targets."""

from __future__ import annotations

import math
import random
from typing import Any

import shapely

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
)
from benchmark.authoring.templates.common import FILES
from benchmark.authoring.templates.common import diagonal_m as _diagonal_m
from benchmark.authoring.templates.common import names as _names
from emulator.world import Target

__all__ = ["TEMPLATES"]

_CATEGORY = "multi_drone_coordination"


def _inspectable(view: SessionView, k: int) -> list[Target]:
    """Fixed point targets and area targets: those a drone can fly over."""
    pool = [t for t in view.points if t.kind == "fixed"] + list(view.areas)
    if len(pool) < k:
        raise TemplateUnfit(f"needs {k} fixed or area targets, the session has {len(pool)}")
    return pool


# ------------------------------------------------------------------ formations and meetings
def _formation_pair(view: SessionView, rng: random.Random) -> TaskDraft:
    a, b = pick(rng, view.drones, 2)
    alt = rng.randint(15, 30)
    for _ in range(40):
        ax, ay = view.free_point(rng)
        spacing = rng.randint(10, 20)
        bearing = math.radians(rng.randrange(0, 360, 15))
        bx = float(round(ax + spacing * math.sin(bearing)))
        by = float(round(ay + spacing * math.cos(bearing)))
        if view.is_free(bx, by):
            break
    else:
        raise TemplateUnfit("no free pair of points for a formation")
    gap = math.dist((ax, ay), (bx, by))
    limit = float(math.ceil(gap) + 3)
    return TaskDraft(
        phrasings=[
            f"Fly a two-drone formation at {alt} m: {a.name} to {fmt_xy(ax, ay)} and {b.name} to "
            f"{fmt_xy(bx, by)}, about {gap:.0f} m apart. Both must keep hovering there, no more "
            f"than {limit:.0f} m from each other.",
            f"Position {a.name} over {fmt_xy(ax, ay)} and {b.name} over {fmt_xy(bx, by)}, both "
            f"at {alt} metres, and hold them in a hover with at most {limit:.0f} m between the "
            f"two drones.",
            f"Formation task: {a.name} holds {fmt_xy(ax, ay)} and {b.name} holds "
            f"{fmt_xy(bx, by)} at an altitude of {alt} m, hovering side by side within "
            f"{limit:.0f} m of one another.",
        ],
        checks=all_of(
            leaf("drone_has_visited_position", drone_id=a.id, x=ax, y=ay, z=float(alt),
                 tolerance=3.0),
            leaf("drone_has_visited_position", drone_id=b.id, x=bx, y=by, z=float(alt),
                 tolerance=3.0),
            leaf("two_drones_distance", drone_1_id=a.id, drone_2_id=b.id, max_distance=limit),
            leaf("drone_hovering", drone_id=a.id, tolerance=0.5),
            leaf("drone_hovering", drone_id=b.id, tolerance=0.5),
        ),
        oracle=[[{"op": "goto", "drone": a.id, "x": ax, "y": ay, "z": alt},
                 {"op": "goto", "drone": b.id, "x": bx, "y": by, "z": alt}],
                [{"op": "hover", "drone": a.id, "duration_s": 5},
                 {"op": "hover", "drone": b.id, "duration_s": 5}]],
        flight_m=_diagonal_m(view),
        hover_s=5.0,
        steps=6,
    )


def _rendezvous(view: SessionView, rng: random.Random) -> TaskDraft:
    team = pick(rng, view.drones, rng.randint(3, min(4, len(view.drones))))
    base_alt = rng.randint(12, 20)
    alts = [base_alt + 5 * k for k in range(len(team))]
    for _ in range(40):
        sx, sy = view.free_point(rng, clearance_m=30.0)
        turn = rng.randrange(0, 360, 10)
        spots = []
        for k in range(len(team)):
            bearing = math.radians(turn + k * 360.0 / len(team))
            radius = rng.randint(6, 12)
            spots.append((float(round(sx + radius * math.sin(bearing))),
                          float(round(sy + radius * math.cos(bearing)))))
        if all(view.is_free(x, y) for x, y in spots):
            break
    else:
        raise TemplateUnfit("no free meeting point")
    assigned = ", ".join(f"{d.name} to {fmt_xy(x, y)} at {z} m"
                         for d, (x, y), z in zip(team, spots, alts, strict=True))
    return TaskDraft(
        phrasings=[
            f"Gather {_names(team)} around {fmt_xy(sx, sy)}, each at its own place and height: "
            f"send {assigned}. Keep them there so that, at the end, every pair of these drones "
            f"is within 45 m of each other.",
            f"Rendezvous near {fmt_xy(sx, sy)}: send {assigned}; hold the group together, all "
            f"pairwise distances 45 m or less.",
            f"Meet up at {fmt_xy(sx, sy)}, each drone in its own slot: {assigned}. Stay grouped, "
            f"with no two of these drones more than 45 m apart.",
        ],
        checks=all_of(
            leaf("drone_group_distance", drone_ids=[d.id for d in team], max_distance=45.0,
                 mode="all_pairs"),
            *(leaf("drone_has_visited_position", drone_id=d.id, x=x, y=y, z=float(z),
                   tolerance=3.0) for d, (x, y), z in zip(team, spots, alts, strict=True)),
        ),
        oracle=[[{"op": "goto", "drone": d.id, "x": x, "y": y, "z": z}
                 for d, (x, y), z in zip(team, spots, alts, strict=True)]],
        flight_m=_diagonal_m(view),
        steps=2 * len(team),
    )


def _fleet_launch(view: SessionView, rng: random.Random) -> TaskDraft:
    alt = rng.randint(10, 30)
    fleet = view.drones
    return TaskDraft(
        phrasings=[
            f"Launch the entire fleet: every one of the {len(fleet)} drones takes off to {alt} m "
            f"and then hovers in place.",
            f"Get all drones airborne at {alt} metres and leave each of them hovering.",
            f"Fleet take-off: climb every drone to an altitude of {alt} m and hold a hover "
            f"there.",
        ],
        checks=all_of(
            leaf("all_drones_have_taken_off", min_altitude=alt - 1.5),
            leaf("all_drones_hovering", tolerance=0.5),
        ),
        oracle=[[{"op": "takeoff", "drone": d.id, "altitude_m": alt} for d in fleet],
                [{"op": "hover", "drone": d.id, "duration_s": 5} for d in fleet]],
        flight_m=float(alt),
        hover_s=5.0,
        steps=2 * len(fleet),
    )


def _sweep_line(view: SessionView, rng: random.Random) -> TaskDraft:
    team = pick(rng, view.drones, rng.randint(3, min(4, len(view.drones))))
    north_m, east_m = rng.randint(50, 120), rng.randint(50, 120)
    base_alt = rng.randint(15, 20)
    alts = [base_alt + 5 * k for k in range(len(team))]
    region = (30.0, 30.0, view.map_w_m - 30.0 - east_m, view.map_h_m - 30.0 - north_m)
    starts: list[tuple[float, float]] = []
    routes: list[shapely.LineString] = []
    for z in alts:
        for _ in range(60):
            x, y = view.free_point(rng, region=region)
            corner, end = (x, y + north_m), (x + east_m, y + north_m)
            route = shapely.LineString([(x, y), corner, end])
            if (view.clear_leg((x, y), corner, z) and view.clear_leg(corner, end, z)
                    and all(route.distance(other) >= 20.0 for other in routes)):
                starts.append((x, y))
                routes.append(route)
                break
        else:
            raise TemplateUnfit("no clear north-then-east route")
    north_min, east_min = round(0.9 * north_m, 1), round(0.9 * east_m, 1)
    assigned = ", ".join(f"{d.name} starting at {fmt_xy(x, y)}, {z} m up"
                         for d, (x, y), z in zip(team, starts, alts, strict=True))
    checks = []
    ops = []
    for d, (x, y), z in zip(team, starts, alts, strict=True):
        checks += [
            leaf("drone_has_visited_position", drone_id=d.id, x=x, y=y, z=float(z),
                 tolerance=3.0),
            leaf("drone_has_moved_directed_distance", drone_id=d.id, min_distance=north_min,
                 heading=0.0, tolerance=5.0),
            leaf("drone_has_moved_directed_distance", drone_id=d.id, min_distance=east_min,
                 heading=90.0, tolerance=5.0),
        ]
        ops += [{"op": "goto", "drone": d.id, "x": x, "y": y, "z": z},
                {"op": "towards", "drone": d.id, "heading_deg": 0.0, "distance_m": north_m},
                {"op": "towards", "drone": d.id, "heading_deg": 90.0, "distance_m": east_m}]
    return TaskDraft(
        phrasings=[
            f"Parallel sweep with {len(team)} drones: {assigned}. Once at its start, each drone "
            f"flies straight north for {north_m} m and then straight east for {east_m} m at its "
            f"altitude.",
            f"Each drone goes to its own start point first ({assigned}); from there it moves "
            f"{north_m} metres due north and afterwards {east_m} metres due east in straight "
            f"lines.",
            f"Sweep line: {assigned}. After reaching the start, every drone heads north "
            f"(heading 0) for {north_m} m, then east (heading 90) for {east_m} m, without "
            f"changing altitude.",
        ],
        checks=all_of(*checks),
        oracle=[ops],
        flight_m=_diagonal_m(view) + north_m + east_m,
        steps=4 * len(team),
    )


# ------------------------------------------------------------------ shared targets
def targets_apart(view: SessionView, rng: random.Random, values: dict[str, Any],
                  entities: dict[str, Any]) -> dict[str, Any]:
    """Hook of cross_check_targets.json: the distance between the two targets (budget)."""
    first, second = entities["target_1"], entities["target_2"]
    return {"flight": math.dist(first.position_m[:2], second.position_m[:2])}



TEMPLATES = (
    Template("formation_pair", _CATEGORY, "medium", _formation_pair, drones=2),
    Template("rendezvous", _CATEGORY, "medium", _rendezvous, drones=3),
    Template("fleet_launch", _CATEGORY, "easy", _fleet_launch),
    Template("sweep_line", _CATEGORY, "hard", _sweep_line, drones=3),
    load_template(FILES / "double_check_target.json"),
    load_template(FILES / "cross_check_targets.json"),
)
