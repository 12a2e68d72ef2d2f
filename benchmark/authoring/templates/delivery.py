"""Delivery: land at a pickup point and a drop point, a round of drops, two parcels at once.

A delivery is a landing: the drone must touch the ground at each listed point (a visit at
z = 0), so the oracle flies there at cruise altitude and lands. The points of one task lie
within a square of at most ``AREA_SIDE_M`` so that a single battery covers the round.
"""

from __future__ import annotations

import math
import random
from collections.abc import Sequence
from typing import Any

from benchmark.authoring.template_files.loader import load_template
from benchmark.authoring.templates.base import (
    SessionView,
    TemplateUnfit,
    fmt_xy,
    leaf,
    tour_length,
)
from benchmark.authoring.templates.common import FILES, spread_points
from benchmark.authoring.templates.common import home_xy as _home_xy
from benchmark.authoring.templates.common import nearest_first as _nearest_first

__all__ = ["AREA_SIDE_M", "TEMPLATES"]

AREA_SIDE_M = 700.0
_TRIES = 60

Point = tuple[float, float]
Node = dict[str, Any]


def _spots(view: SessionView, rng: random.Random, n: int, min_gap_m: float) -> list[Point]:
    return spread_points(view, rng, n, min_gap_m, AREA_SIDE_M, _TRIES)


def _landed_at(drone_id: str, point: Point) -> Node:
    return leaf("drone_has_visited_position", drone_id=drone_id, x=point[0], y=point[1], z=0.0,
                tolerance=3.0)


def _land_ops(drone_id: str, points: Sequence[Point], alt: int) -> list[Node]:
    ops: list[Node] = []
    for x, y in points:
        ops.append({"op": "goto", "drone": drone_id, "x": x, "y": y, "z": alt})
        ops.append({"op": "land", "drone": drone_id})
    return ops


def _ends(drone_id: str, point: Point, landings: int) -> list[Node]:
    """Checks that the drone landed `landings` times and rests on the ground at point."""
    return [leaf("drone_has_landed", drone_id=drone_id, min_count=landings),
            leaf("drone_position", drone_id=drone_id, x=point[0], y=point[1], tolerance=3.0),
            leaf("drone_on_ground", drone_id=drone_id, tolerance=0.5)]


def parcel_spots(view: SessionView, rng: random.Random, values: dict[str, Any],
                 entities: dict[str, Any]) -> dict[str, Any]:
    """Hook of parcel_delivery.json: pickup and drop spots 150 m apart or more, and the
    distance between them (for the budget)."""
    pickup, drop = _spots(view, rng, 2, 150.0)
    return {"pickup": pickup, "drop": drop, "flight": math.dist(pickup, drop)}



def drop_round(view: SessionView, rng: random.Random, values: dict[str, Any],
               entities: dict[str, Any]) -> dict[str, Any]:
    """Hook of multi_drop.json: three drop spots, nearest first from the drone's home, as
    listed in the text, and the round's length (budget)."""
    drone = entities["drone_1"]
    drops = _nearest_first(_home_xy(view, view.drones.index(drone)), _spots(view, rng, 3, 100.0))
    return {"drop1": drops[0], "drop2": drops[1], "drop3": drops[2],
            "listed": ", ".join(fmt_xy(*p) for p in drops), "flight": tour_length(drops)}



def two_rounds(view: SessionView, rng: random.Random, values: dict[str, Any],
               entities: dict[str, Any]) -> dict[str, Any]:
    """Hook of team_delivery.json: a pickup and a drop spot per drone, the drops 100 m apart
    or more, and the longer leg (budget)."""
    for _ in range(_TRIES):
        pick_a, drop_a, pick_b, drop_b = _spots(view, rng, 4, 60.0)
        if math.dist(drop_a, drop_b) >= 100.0:
            break
    else:
        raise TemplateUnfit("no two drop points 100 m apart")
    return {"pick_a": pick_a, "drop_a": drop_a, "pick_b": pick_b, "drop_b": drop_b,
            "flight": max(math.dist(pick_a, drop_a), math.dist(pick_b, drop_b))}



TEMPLATES = (
    load_template(FILES / "parcel_delivery.json"),
    load_template(FILES / "multi_drop.json"),
    load_template(FILES / "team_delivery.json"),
)
