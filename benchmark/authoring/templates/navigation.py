"""Navigation: checkpoints, ordered tours, a rectangular patrol, compass legs, landings, surveys.

Tours are kept short enough for one battery: survey points lie on a serpentine through a
grid of cells that starts at the cell nearest the drone's home, and a route is shrunk until
its length fits ``MAX_ROUTE_M``.
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
from benchmark.authoring.templates.common import FILES
from benchmark.authoring.templates.common import diagonal_m as _diagonal_m
from benchmark.authoring.templates.common import home_xy as _home_xy
from benchmark.authoring.templates.common import visited as _visited

__all__ = ["MAX_ROUTE_M", "TEMPLATES"]

MAX_ROUTE_M = 3000.0  # longest listed route of a survey, home to the last point
_TRIES = 60
_LEG_SAMPLES = 6  # candidate points per survey cell

Point = tuple[float, float]
Rect = tuple[float, float, float, float]
Node = dict[str, Any]


def _xy_list(points: Sequence[Point]) -> str:
    return ", ".join(fmt_xy(x, y) for x, y in points)


def _fly_route(drone_id: str, points: Sequence[Point], alt: int) -> list[Node]:
    """Oracle ops: go to the first point, then follow the rest in order at one altitude."""
    ops: list[Node] = [{"op": "goto", "drone": drone_id, "x": points[0][0], "y": points[0][1],
                        "z": alt}]
    if len(points) > 1:
        ops.append({"op": "path", "drone": drone_id,
                    "points": [[x, y, alt] for x, y in points[1:]]})
    return ops


def _grid_route(view: SessionView, rng: random.Random, n: int, rect: Rect,
                start_xy: Point, alt: int) -> list[Point]:
    """n free points, one per grid cell over rect, in serpentine order from the corner of
    rect nearest start_xy; each point is preferably reached by a clear straight leg at alt
    from the one before, so the route needs few detours."""
    x0, y0, x1, y1 = rect
    w, h = x1 - x0, y1 - y0
    cols = max(1, min(n, round(math.sqrt(n * w / h))))
    rows = math.ceil(n / cols)
    cw, ch = w / cols, h / rows
    flip_x = start_xy[0] > (x0 + x1) / 2
    flip_y = start_xy[1] > (y0 + y1) / 2
    cells: list[tuple[int, int]] = []
    for r in range(rows):
        row = list(range(cols)) if r % 2 == 0 else list(range(cols - 1, -1, -1))
        cells.extend((c, r) for c in row)
    points: list[Point] = []
    for c, r in cells[:n]:
        c = cols - 1 - c if flip_x else c
        r = rows - 1 - r if flip_y else r
        cell = (x0 + (c + 0.15) * cw, y0 + (r + 0.15) * ch,
                x0 + (c + 0.85) * cw, y0 + (r + 0.85) * ch)
        first = point = view.free_point(rng, region=cell, tries=150)
        for _ in range(_LEG_SAMPLES if points else 0):
            if view.clear_leg(points[-1], point, alt):
                break
            point = view.free_point(rng, region=cell, tries=150)
        else:
            point = first
        points.append(point)
    return points


def _square(view: SessionView, rng: random.Random, side_m: float) -> Rect:
    """A random square (or the largest that fits) of side side_m inside the map's 30 m margin."""
    sx, sy = min(side_m, view.map_w_m - 60.0), min(side_m, view.map_h_m - 60.0)
    x0 = rng.uniform(30.0, view.map_w_m - 30.0 - sx)
    y0 = rng.uniform(30.0, view.map_h_m - 30.0 - sy)
    return (x0, y0, x0 + sx, y0 + sy)


def _survey(view: SessionView, rng: random.Random, n: int, start_xy: Point, alt: int,
            side_m: float, max_route_m: float, halves: int = 1) -> list[list[Point]]:
    """`halves` routes of n points each, over the halves (west/east) of one square, each
    route (from start_xy) no longer than max_route_m; the square shrinks until they fit."""
    for _ in range(_TRIES):
        x0, y0, x1, y1 = _square(view, rng, side_m)
        step = (x1 - x0) / halves
        try:
            routes = [_grid_route(view, rng, n, (x0 + k * step, y0, x0 + (k + 1) * step, y1),
                                  start_xy, alt) for k in range(halves)]
        except TemplateUnfit:
            continue
        if all(tour_length([start_xy, *r]) <= max_route_m for r in routes):
            return routes
        side_m *= 0.9
    raise TemplateUnfit(f"no survey of {n} points within {max_route_m:.0f} m")


def _waypoint_tour(view: SessionView, rng: random.Random) -> TaskDraft:
    (d,) = pick(rng, view.drones, 1)
    home = _home_xy(view, view.drones.index(d))
    alt = rng.randint(15, 25)
    n = rng.randint(4, 5)
    (points,) = _survey(view, rng, n, home, alt, 700.0, MAX_ROUTE_M)
    listed = _xy_list(points)
    return TaskDraft(
        phrasings=[
            f"Fly {d.name} at {alt} m through these waypoints in this order: {listed}.",
            f"Take {d.name} up to {alt} metres and visit, one after the other, the points "
            f"{listed}.",
            f"{d.name} has a {n}-waypoint route to fly at {alt} m altitude: {listed} "
            f"(keep the order).",
        ],
        checks=all_of(*_visited(d.id, points, alt)),
        oracle=[_fly_route(d.id, points, alt)],
        flight_m=tour_length(points) + _diagonal_m(view),
        steps=1 + n,
    )


def _patrol_loop(view: SessionView, rng: random.Random) -> TaskDraft:
    (d,) = pick(rng, view.drones, 1)
    alt = rng.randint(12, 30)
    longest = int(min(400.0, 0.45 * min(view.map_w_m, view.map_h_m)))
    for attempt in range(2 * _TRIES):
        w, h = rng.randint(150, longest), rng.randint(150, longest)
        x, y = view.free_point(rng, region=(30.0, 30.0, view.map_w_m - 30.0 - w,
                                            view.map_h_m - 30.0 - h))
        corners = [(x, y), (x + w, y), (x + w, y + h), (x, y + h)]
        if all(view.is_free(cx, cy) for cx, cy in corners) and (attempt >= _TRIES or all(
                view.clear_leg(p, q, alt) for p, q in zip(corners, corners[1:] + corners[:1],
                                                           strict=True))):
            break  # clear sides preferred; later attempts accept sides needing detours
    else:
        raise TemplateUnfit("no rectangle with four free corners")
    first = rng.randrange(4)
    corners = corners[first:] + corners[:first]
    if rng.random() < 0.5:
        corners = [corners[0], *reversed(corners[1:])]
    perimeter = 2.0 * (w + h)
    loop = [*corners, corners[0]]
    listed = _xy_list(corners)
    start = fmt_xy(*corners[0])
    return TaskDraft(
        phrasings=[
            f"Patrol a rectangle with {d.name} at {alt} m: fly to the corners {listed} in "
            f"that order, then close the loop back at {start} and hover there.",
            f"{d.name} must fly one lap of the rectangular circuit {listed} at {alt} metres, "
            f"in the given order, ending airborne over the first corner {start}.",
            f"At an altitude of {alt} m, take {d.name} around the four corners {listed} and "
            f"return to {start} to finish the lap, holding position there.",
        ],
        checks=all_of(
            *_visited(d.id, corners, alt),
            leaf("drone_has_moved_distance", drone_id=d.id,
                 min_distance=float(round(0.9 * perimeter))),
            leaf("drone_position", drone_id=d.id, x=corners[0][0], y=corners[0][1],
                 z=float(alt), tolerance=3.0),
        ),
        oracle=[_fly_route(d.id, loop, alt)],
        flight_m=perimeter + _diagonal_m(view),
        steps=6,
    )


def compass_start(view: SessionView, rng: random.Random, values: dict[str, Any],
                  entities: dict[str, Any]) -> dict[str, Any]:
    """Hook of compass_legs.json: leg lengths and a start whose north-then-east legs are
    clear at the altitude, the checks' 90 % of each, and the flight (budget)."""
    alt = values["alt"]
    for _ in range(_TRIES):
        north, east = rng.randint(60, 150), rng.randint(60, 150)
        sx, sy = view.free_point(rng, region=(30.0, 30.0, view.map_w_m - 30.0 - east,
                                              view.map_h_m - 30.0 - north))
        turn = (sx, sy + north)
        if view.clear_leg((sx, sy), turn, alt) and view.clear_leg(turn, (sx + east, turn[1]),
                                                                   alt):
            break
    else:
        raise TemplateUnfit("no clear north-then-east legs")
    return {"start": (sx, sy), "north": north, "east": east,
            "north_min": round(0.9 * north, 1), "east_min": round(0.9 * east, 1),
            "flight": north + east}



def _long_survey(view: SessionView, rng: random.Random) -> TaskDraft:
    (d,) = pick(rng, view.drones, 1)
    home = _home_xy(view, view.drones.index(d))
    alt = rng.randint(20, 35)
    n = rng.randint(8, 12)
    (route,) = _survey(view, rng, n + 1, home, alt, 1000.0, MAX_ROUTE_M)
    points, (fx, fy) = route[:n], route[n]
    listed = _xy_list(points)
    end = fmt_xy(fx, fy)
    return TaskDraft(
        phrasings=[
            f"Survey flight for {d.name} at {alt} m: visit the {n} points {listed} in this "
            f"order, then fly to {end} and land there.",
            f"{d.name} should cruise at {alt} metres over each of these survey points in "
            f"turn: {listed}. Finish by landing at {end}.",
            f"Take {d.name} on a long survey at an altitude of {alt} m through {listed} (in "
            f"order), and end the flight on the ground at {end}.",
        ],
        checks=all_of(
            *_visited(d.id, points, alt),
            leaf("drone_position", drone_id=d.id, x=fx, y=fy, tolerance=3.0),
            leaf("drone_on_ground", drone_id=d.id, tolerance=0.5),
        ),
        oracle=[[*_fly_route(d.id, route, alt), {"op": "land", "drone": d.id}]],
        flight_m=tour_length(route) + _diagonal_m(view),
        steps=n + 3,
    )


def _dual_survey(view: SessionView, rng: random.Random) -> TaskDraft:
    a, b = pick(rng, view.drones, 2)
    home = _home_xy(view, view.drones.index(a))
    alt_a = rng.randint(18, 28)
    alt_b = alt_a + rng.choice((6, 8, 10))
    n = rng.randint(5, 6)
    route_a, route_b = _survey(view, rng, n + 1, home, alt_a, 1000.0, MAX_ROUTE_M,
                                halves=2)
    plans = ((a, alt_a, route_a), (b, alt_b, route_b))
    lists = [(_xy_list(r[:n]), fmt_xy(*r[n])) for _, _, r in plans]
    checks: list[Node] = []
    ops: list[Node] = []
    for drone, alt, route in plans:
        checks.extend(_visited(drone.id, route[:n], alt))
        checks.append(leaf("drone_position", drone_id=drone.id, x=route[n][0], y=route[n][1],
                           tolerance=3.0))
        checks.append(leaf("drone_on_ground", drone_id=drone.id, tolerance=0.5))
        ops.extend([*_fly_route(drone.id, route, alt), {"op": "land", "drone": drone.id}])
    (list_a, end_a), (list_b, end_b) = lists
    return TaskDraft(
        phrasings=[
            f"Run two surveys at once. {a.name} flies at {alt_a} m over {list_a} in order and "
            f"lands at {end_a}; {b.name} flies at {alt_b} m over {list_b} in order and lands "
            f"at {end_b}.",
            f"Split the survey between {a.name} and {b.name}. {a.name} ({alt_a} metres): "
            f"{list_a}, then land at {end_a}. {b.name} ({alt_b} metres): {list_b}, then land "
            f"at {end_b}. Keep each list in order.",
            f"{a.name} and {b.name} survey in parallel: the first visits {list_a} at {alt_a} m "
            f"and touches down at {end_a}; the second visits {list_b} at {alt_b} m and touches "
            f"down at {end_b}.",
        ],
        checks=all_of(*checks),
        oracle=[ops],
        flight_m=max(tour_length(route_a), tour_length(route_b)) + _diagonal_m(view),
        steps=2 * (n + 3),
    )


TEMPLATES = (
    load_template(FILES / "checkpoint.json"),
    Template("waypoint_tour", "navigation", "medium", _waypoint_tour),
    Template("patrol_loop", "navigation", "medium", _patrol_loop),
    load_template(FILES / "compass_legs.json"),
    load_template(FILES / "precision_landing.json"),
    Template("long_survey", "navigation", "hard", _long_survey),
    Template("dual_survey", "navigation", "hard", _dual_survey, drones=2),
)
