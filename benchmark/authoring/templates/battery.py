"""Battery management: charge at a station, a tour that ends on a charger, a reserve at home.

Charging happens only on the ground on a charging station (a session's ``waypoint`` targets);
a charge counts once the battery is full. Charging time in the budget is the drain of the
flight estimated at ``DRAIN_PCT_PER_M`` divided by the station's rate, plus a margin.
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
from benchmark.authoring.templates.common import nearest_first as _nearest_first
from benchmark.authoring.templates.common import visited as _visited
from emulator.world import Target

__all__ = ["DRAIN_PCT_PER_M", "MAX_RESERVE_TOUR_M", "TEMPLATES"]

DRAIN_PCT_PER_M = 0.02  # a generous drain per metre flown at cruise speed, with headwind
MAX_RESERVE_TOUR_M = 1800.0  # home -> three points -> home, for the 50 % reserve task
_TRIES = 60

Point = tuple[float, float]
Node = dict[str, Any]
Rect = tuple[float, float, float, float]


def _around(center: Point, half_m: float) -> Rect:
    return (center[0] - half_m, center[1] - half_m, center[0] + half_m, center[1] + half_m)


def _spaced(view: SessionView, rng: random.Random, n: int, region: Rect,
            min_gap_m: float, away_from: Point) -> list[Point]:
    """n free points in region, min_gap_m apart and from away_from."""
    points: list[Point] = []
    for _ in range(20 * n):
        p = view.free_point(rng, region=region)
        if all(math.dist(p, q) >= min_gap_m for q in [away_from, *points]):
            points.append(p)
            if len(points) == n:
                return points
    raise TemplateUnfit(f"no {n} free points {min_gap_m:.0f} m apart in {region}")


def _charge_s(station: Target, flight_m: float) -> float:
    """Seconds to refill what a flight of flight_m drains, at the station's rate, plus 30 s."""
    rate = station.charge_rate_pct_s or 0.1
    return round(min(100.0, DRAIN_PCT_PER_M * flight_m) / rate + 30.0, 1)


def _charged_on(drone_id: str, station: Target) -> list[Node]:
    return [leaf("drone_has_charged", drone_id=drone_id),
            leaf("drone_battery_level", drone_id=drone_id, min_level=99.0),
            leaf("drone_on_ground", drone_id=drone_id, tolerance=0.5),
            leaf("drone_in_target", drone_id=drone_id, target_id=station.id)]


def _route_ops(drone_id: str, points: Sequence[Point], alt: int) -> list[Node]:
    ops: list[Node] = [{"op": "goto", "drone": drone_id, "x": points[0][0], "y": points[0][1],
                        "z": alt}]
    if len(points) > 1:
        ops.append({"op": "path", "drone": drone_id,
                    "points": [[x, y, alt] for x, y in points[1:]]})
    return ops


def station_charge(view: SessionView, rng: random.Random, values: dict[str, Any],
                   entities: dict[str, Any]) -> dict[str, Any]:
    """Hook of recharge_stop.json: where the station is and how long charging takes."""
    station = entities["station"]
    return {"where": (station.position_m[0], station.position_m[1]),
            "charge_s": _charge_s(station, _diagonal_m(view))}



def _tour_then_recharge(view: SessionView, rng: random.Random) -> TaskDraft:
    (d,) = pick(rng, view.drones, 1)
    station = rng.choice(view.stations)
    sxy = (station.position_m[0], station.position_m[1])
    alt = rng.randint(15, 30)
    n = rng.randint(2, 3)
    points = _nearest_first(_home_xy(view, view.drones.index(d)),
                            _spaced(view, rng, n, _around(sxy, 350.0), 80.0, sxy))
    listed = ", ".join(fmt_xy(*p) for p in points)
    where = fmt_xy(*sxy)
    flight = tour_length([*points, sxy]) + _diagonal_m(view)
    return TaskDraft(
        phrasings=[
            f"Fly {d.name} at {alt} m over the points {listed} in this order, then land on "
            f"{station.name} at {where} and charge the battery to full, staying on the pad.",
            f"{d.name}: visit {listed} one after another at {alt} metres; afterwards recharge "
            f"at {station.name} {where}, landing on it and waiting until the battery is full.",
            f"Route for {d.name} at an altitude of {alt} m: {listed}. Finish by landing on the "
            f"charging station {station.name}, located at {where}, and filling the battery to "
            f"100 %.",
        ],
        checks=all_of(*_visited(d.id, points, alt), *_charged_on(d.id, station)),
        oracle=[[*_route_ops(d.id, points, alt),
                 {"op": "charge", "drone": d.id, "station": station.id}]],
        flight_m=flight,
        hover_s=_charge_s(station, flight),
        steps=n + 4,
    )


def _return_with_reserve(view: SessionView, rng: random.Random) -> TaskDraft:
    (d,) = pick(rng, view.drones, 1)
    home = _home_xy(view, view.drones.index(d))
    alt = rng.randint(15, 30)
    for _ in range(_TRIES):
        points = _nearest_first(home, _spaced(view, rng, 3, _around(home, 450.0), 80.0, home))
        if tour_length([home, *points, home]) <= MAX_RESERVE_TOUR_M:
            break
    else:
        raise TemplateUnfit(f"no three-point tour within {MAX_RESERVE_TOUR_M:.0f} m of home")
    listed = ", ".join(fmt_xy(*p) for p in points)
    return TaskDraft(
        phrasings=[
            f"Fly {d.name} at {alt} m through {listed} in this order, then return it to its "
            f"home position and land, with at least 50 % battery left.",
            f"{d.name}: a short tour at {alt} metres over {listed}, then back home to land. "
            f"Keep a reserve: the battery must still be at 50 % or more at the end.",
            f"Take {d.name} to {listed} one after another at {alt} m altitude and bring it "
            f"home to land, without letting the battery drop below 50 %.",
        ],
        checks=all_of(
            *_visited(d.id, points, alt),
            leaf("drone_at_home", drone_id=d.id, tolerance=3.0),
            leaf("drone_on_ground", drone_id=d.id, tolerance=0.5),
            leaf("drone_battery_level", drone_id=d.id, min_level=50.0),
        ),
        oracle=[[*_route_ops(d.id, points, alt),
                 {"op": "home", "drone": d.id, "altitude_m": alt}]],
        flight_m=tour_length([home, *points, home]) + _diagonal_m(view),
        steps=6,
    )


TEMPLATES = (
    load_template(FILES / "recharge_stop.json"),
    Template("tour_then_recharge", "battery_management", "hard", _tour_then_recharge,
             stations=1),
    Template("return_with_reserve", "battery_management", "medium", _return_with_reserve,
             stations=1),
)
