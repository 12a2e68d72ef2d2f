"""Target tracking (the target_tracking family): follow a moving target, intercept it inside a
zone, keep every moving target tracked, hand a target over between drones, photograph one.

Agents are told where a target moves (the middle of its track); they find it with their
sensors. A tracking period follows MultiUAV-Plat: it runs from a reach to TRACKING_WINDOW_S
after the last reach, so "follow for N s" checks a period of N + TRACKING_WINDOW_S seconds.
"""

from __future__ import annotations

import math
import random
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
)
from benchmark.authoring.templates.common import FILES
from benchmark.authoring.templates.common import diagonal_m as _diagonal_m
from benchmark.authoring.templates.common import names as _names
from benchmark.scoring.validators.targets import TRACKING_WINDOW_S
from emulator.world import Target

__all__ = ["TEMPLATES", "track_points"]

_CATEGORY = "target_tracking"
_FAMILY = ("target_tracking",)
HOP_S = 4.0  # the oracle re-aims at a followed target this often (two tool calls)


def track_points(target: Target) -> list[tuple[float, float]]:
    """The points a moving target's track runs through (its segment or its path)."""
    motion = target.motion
    if motion is None or motion.mode == "stationary":
        return [(target.position_m[0], target.position_m[1])]
    if motion.mode == "velocity":
        x, y, _ = motion.start_m
        vx, vy, _ = motion.velocity_m_s
        return [(x, y), (x + vx * motion.duration_s, y + vy * motion.duration_s)]
    return [(motion.start_m[0], motion.start_m[1]), *((p[0], p[1]) for p in motion.path_m)]


def _middle(target: Target) -> tuple[float, float]:
    points = track_points(target)
    xs, ys = zip(*points, strict=True)
    return (min(xs) + max(xs)) / 2.0, (min(ys) + max(ys)) / 2.0


def _where(target: Target) -> str:
    x, y = _middle(target)
    return f"{target.name} (it moves around {fmt_xy(x, y)})"


def _follow_steps(duration_s: float) -> int:
    return 6 + 2 * math.ceil(duration_s / HOP_S)


def _altitude(rng: random.Random) -> int:
    return rng.randint(15, 30)


# ------------------------------------------------------------------ one drone, one target
def follow_terms(view: SessionView, rng: random.Random, values: dict[str, Any],
                 entities: dict[str, Any]) -> dict[str, Any]:
    """Hook of follow_moving_target.json: where the target moves, the tracked time the check
    asks for, and the budget of following it."""
    seconds = values["seconds"]
    return {"mid": _middle(entities["target_1"]), "tracked_s": seconds + TRACKING_WINDOW_S,
            "hold_s": seconds + 30.0, "steps": _follow_steps(seconds)}



def intercept_zone(view: SessionView, rng: random.Random, values: dict[str, Any],
                   entities: dict[str, Any]) -> dict[str, Any]:
    """Hook of intercept_in_zone.json: a zone on the moving target's track (and its radius),
    and where the target moves."""
    target = entities["target_1"]
    points = track_points(target)
    if len(points) < 2:
        raise TemplateUnfit(f"{target.id} does not move")
    k = rng.randrange(len(points) - 1)
    f = rng.uniform(0.25, 0.75)
    (ax, ay), (bx, by) = points[k], points[k + 1]
    zx, zy = float(round(ax + f * (bx - ax))), float(round(ay + f * (by - ay)))
    radius = float(rng.randint(10, 15))
    return {"zone": (zx, zy), "radius": radius, "radius_m": f"{radius:.0f}",
            "mid": _middle(target)}



def track_middle(view: SessionView, rng: random.Random, values: dict[str, Any],
                 entities: dict[str, Any]) -> dict[str, Any]:
    """Hook of photograph_moving_target.json: the middle of the moving target's track."""
    return {"mid": _middle(entities["target_1"])}



# ------------------------------------------------------------------ teams
def _all_tracked(view: SessionView, rng: random.Random) -> TaskDraft:
    movers = list(view.movers)
    if len(view.drones) < len(movers):
        raise TemplateUnfit("fewer drones than moving targets")
    drones = pick(rng, view.drones, len(movers))
    seconds = rng.choice((20, 30))
    alt = _altitude(rng)
    pairs = list(zip(drones, movers, strict=True))
    return TaskDraft(
        phrasings=[
            f"Keep every moving target tracked: each of {_names(movers)} must stay within the "
            f"task radius of some drone for at least {seconds} s. Use {_names(drones)}, "
            f"flying at {alt} m.",
            f"Track all {len(movers)} moving targets ({_names(movers)}) for {seconds} seconds "
            f"each, one drone per target, with {_names(drones)} at {alt} m.",
            f"Assign {_names(drones)} to the moving targets {_names(movers)} and have each "
            f"target followed for {seconds} s at an altitude of {alt} m.",
        ],
        checks=all_of(*(leaf("moving_target_tracked", target_id=t.id,
                             min_duration=float(seconds + TRACKING_WINDOW_S))
                        for t in movers)),
        oracle=[[{"op": "track", "drone": d.id, "target": t.id, "duration_s": seconds,
                  "altitude_m": alt} for d, t in pairs]],
        flight_m=_diagonal_m(view), hover_s=seconds + 30.0, steps=len(pairs) *
        _follow_steps(seconds),
    )


def _handover(view: SessionView, rng: random.Random) -> TaskDraft:
    first, second = pick(rng, view.drones, 2)
    target = pick(rng, view.movers, 1)[0]
    a_s, b_s = rng.choice((15, 20)), rng.choice((15, 20))
    alt_a = _altitude(rng)
    alt_b = alt_a + 5 if alt_a <= 25 else alt_a - 5
    return TaskDraft(
        phrasings=[
            f"{first.name} follows {_where(target)} for {a_s} s at {alt_a} m, then hands it "
            f"over to {second.name}, which follows it for another {b_s} s at {alt_b} m.",
            f"Relay tracking of {target.name} (it moves around {fmt_xy(*_middle(target))}): "
            f"first {first.name} for {a_s} seconds ({alt_a} m), then {second.name} for "
            f"{b_s} seconds ({alt_b} m).",
            f"Hand-over task: {first.name} tracks {target.name} for {a_s} s at {alt_a} m; "
            f"{second.name} takes over and tracks it {b_s} s more at {alt_b} m.",
        ],
        checks=all_of(
            leaf("moving_target_tracked", target_id=target.id, drone_id=first.id,
                 min_duration=float(a_s + TRACKING_WINDOW_S)),
            leaf("moving_target_tracked", target_id=target.id, drone_id=second.id,
                 min_duration=float(b_s + TRACKING_WINDOW_S)),
        ),
        oracle=[[{"op": "track", "drone": first.id, "target": target.id, "duration_s": a_s,
                  "altitude_m": alt_a}],
                [{"op": "track", "drone": second.id, "target": target.id, "duration_s": b_s,
                  "altitude_m": alt_b}]],
        flight_m=2 * _diagonal_m(view), hover_s=a_s + b_s + 60.0,
        steps=_follow_steps(a_s) + _follow_steps(b_s),
    )


TEMPLATES: tuple[Template, ...] = (
    load_template(FILES / "follow_moving_target.json"),
    load_template(FILES / "intercept_in_zone.json"),
    load_template(FILES / "photograph_moving_target.json"),
    Template("track_every_moving_target", _CATEGORY, "hard", _all_tracked, drones=2,
             moving_targets=2, families=_FAMILY),
    Template("hand_over_target", _CATEGORY, "hard", _handover, drones=2, moving_targets=1,
             families=_FAMILY),
)
