"""Basic operations: take-off, altitude, heading, a round trip home, a new home."""

from __future__ import annotations

import math
import random

from benchmark.templates.base import (
    SessionView,
    TaskDraft,
    Template,
    all_of,
    fmt_xy,
    leaf,
    pick,
)

__all__ = ["TEMPLATES"]


def _takeoff_hold(view: SessionView, rng: random.Random) -> TaskDraft:
    (d,) = pick(rng, view.drones, 1)
    alt = rng.randint(8, 25)
    return TaskDraft(
        phrasings=[
            f"Take off with {d.name} to {alt} m and hold position there.",
            f"{d.name}: climb to an altitude of {alt} metres and hover.",
            f"Get {d.name} airborne at {alt} m and keep it hovering in place.",
        ],
        checks=all_of(
            leaf("drone_altitude", drone_id=d.id, expected_altitude=float(alt), tolerance=2.0),
            leaf("drone_hovering", drone_id=d.id, tolerance=0.5),
            leaf("drone_on_ground", expect=False, drone_id=d.id, tolerance=1.5),
        ),
        oracle=[[{"op": "takeoff", "drone": d.id, "altitude_m": alt}]],
        steps=1,
    )


def _climb_and_face(view: SessionView, rng: random.Random) -> TaskDraft:
    (d,) = pick(rng, view.drones, 1)
    alt = rng.randint(10, 20)
    heading = rng.randrange(0, 360, 5)
    return TaskDraft(
        phrasings=[
            f"Launch {d.name} to {alt} m, then turn it to face a heading of {heading} degrees.",
            f"Have {d.name} take off to {alt} metres and rotate until it points at "
            f"{heading} degrees (compass).",
            f"{d.name} should hover at {alt} m with its nose at bearing {heading} deg.",
        ],
        checks=all_of(
            leaf("drone_heading", drone_id=d.id, expected_heading=float(heading), tolerance=5.0),
            leaf("drone_altitude", drone_id=d.id, expected_altitude=float(alt), tolerance=2.0),
        ),
        oracle=[[{"op": "takeoff", "drone": d.id, "altitude_m": alt},
                 {"op": "rotate", "drone": d.id, "heading_deg": heading}]],
        steps=2,
    )


def _altitude_change(view: SessionView, rng: random.Random) -> TaskDraft:
    (d,) = pick(rng, view.drones, 1)
    first = rng.randint(8, 15)
    second = rng.randint(20, 40)
    return TaskDraft(
        phrasings=[
            f"Take off with {d.name} to {first} m, then change its altitude to {second} m "
            f"and hover.",
            f"{d.name}: go up to {first} metres first, then climb on to {second} metres and "
            f"stay there.",
            f"Raise {d.name} to {first} m, and once there move it to {second} m altitude.",
        ],
        checks=all_of(
            leaf("drone_has_taken_off", drone_id=d.id, min_altitude=float(first),
                 max_altitude=float(first), tolerance=1.5),
            leaf("drone_altitude", drone_id=d.id, expected_altitude=float(second),
                 tolerance=2.0),
            leaf("drone_hovering", drone_id=d.id, tolerance=0.5),
        ),
        oracle=[[{"op": "takeoff", "drone": d.id, "altitude_m": first},
                 {"op": "altitude", "drone": d.id, "altitude_m": second}]],
        steps=2,
    )


def _round_trip_home(view: SessionView, rng: random.Random) -> TaskDraft:
    (d,) = pick(rng, view.drones, 1)
    alt = rng.randint(15, 30)
    x, y = view.free_point(rng, region=view.region(0.3, 0.3, 0.8, 0.8))
    return TaskDraft(
        phrasings=[
            f"Fly {d.name} out to {fmt_xy(x, y)} at {alt} m, then bring it back home and land.",
            f"Send {d.name} to the point {fmt_xy(x, y)} (altitude {alt} m) and return it to "
            f"its home position, landed.",
            f"{d.name} must visit {fmt_xy(x, y)} at {alt} metres and finish on the ground at "
            f"home.",
        ],
        checks=all_of(
            leaf("drone_has_taken_off", drone_id=d.id, min_altitude=5.0),
            leaf("drone_has_visited_position", drone_id=d.id, x=x, y=y, z=float(alt),
                 tolerance=3.0),
            leaf("drone_has_landed", drone_id=d.id, min_count=1),
            leaf("drone_at_home", drone_id=d.id, tolerance=3.0),
            leaf("drone_on_ground", drone_id=d.id, tolerance=0.5),
        ),
        oracle=[[{"op": "goto", "drone": d.id, "x": x, "y": y, "z": alt},
                 {"op": "home", "drone": d.id, "altitude_m": alt}]],
        flight_m=2 * math.hypot(view.map_w_m, view.map_h_m),
        steps=5,
    )


def _new_home(view: SessionView, rng: random.Random) -> TaskDraft:
    (d,) = pick(rng, view.drones, 1)
    alt = rng.randint(15, 25)
    hx, hy = view.free_point(rng, region=view.region(0.2, 0.2, 0.5, 0.5))
    qx, qy = view.free_point(rng, region=view.region(0.5, 0.5, 0.85, 0.85))
    return TaskDraft(
        phrasings=[
            f"Move {d.name}'s home: fly it to {fmt_xy(hx, hy)} at {alt} m, land there and make "
            f"that spot its new home. Then fly to {fmt_xy(qx, qy)} at {alt} m and return to "
            f"the new home and land.",
            f"Relocate the home of {d.name} to {fmt_xy(hx, hy)} (land there and set it as "
            f"home), then send it to {fmt_xy(qx, qy)} at {alt} metres and bring it back home "
            f"to land.",
            f"{d.name}: land at {fmt_xy(hx, hy)} and register it as home; afterwards visit "
            f"{fmt_xy(qx, qy)} at {alt} m and come home to land.",
        ],
        checks=all_of(
            leaf("drone_has_visited_position", drone_id=d.id, x=qx, y=qy, z=float(alt),
                 tolerance=3.0),
            leaf("drone_position", drone_id=d.id, x=hx, y=hy, tolerance=3.0),
            leaf("drone_at_home", drone_id=d.id, tolerance=3.0),
            leaf("drone_on_ground", drone_id=d.id, tolerance=0.5),
            leaf("drone_has_landed", drone_id=d.id, min_count=2),
        ),
        oracle=[[{"op": "goto", "drone": d.id, "x": hx, "y": hy, "z": alt},
                 {"op": "land", "drone": d.id},
                 {"op": "set_home", "drone": d.id},
                 {"op": "goto", "drone": d.id, "x": qx, "y": qy, "z": alt},
                 {"op": "home", "drone": d.id, "altitude_m": alt}]],
        flight_m=3 * math.hypot(view.map_w_m, view.map_h_m),
        steps=9,
    )


TEMPLATES = (
    Template("takeoff_hold", "basic_operations", "easy", _takeoff_hold),
    Template("climb_and_face", "basic_operations", "easy", _climb_and_face),
    Template("altitude_change", "basic_operations", "easy", _altitude_change),
    Template("round_trip_home", "basic_operations", "easy", _round_trip_home),
    Template("new_home", "basic_operations", "medium", _new_home),
)
