"""History checks: what a drone did inside the window, from its events and its trajectory."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from benchmark.scoring.validators._errors import EvaluationError
from benchmark.scoring.validators.context import AIRBORNE_M, CheckContext
from benchmark.scoring.validators.endpoint import (
    Endpoint,
    Outcome,
    Params,
    Runner,
    Validator,
    ordered,
)
from benchmark.scoring.validators.geometry import (
    heading_delta_deg,
    point_segment_distance,
    segment_bearing_deg,
)
from benchmark.scoring.validators.params import (
    ParamSpec,
    entity,
    flag,
    integer,
    number,
    point,
    text,
)
from benchmark.scoring.validators.state import is_on_ground
from benchmark.scoring.validators.track import Track
from emulator.truth_events import TruthEventKind

__all__ = [
    "CHARGE_END_EVENTS",
    "DEFAULT_HOVER_S",
    "FULL_BATTERY_PCT",
    "HISTORY_ENDPOINTS",
    "HOVER_MAX_SPEED_M_S",
    "MIN_DIRECTED_STEP_M",
    "hover_periods",
]

HOVER_MAX_SPEED_M_S = 0.3
DEFAULT_HOVER_S = 1.0
MIN_DIRECTED_STEP_M = 1e-3
FULL_BATTERY_PCT = 99.9
CHARGE_END_EVENTS = (TruthEventKind.CHARGED, TruthEventKind.ARM, TruthEventKind.TAKEOFF,
                     TruthEventKind.OPERATOR_PLACE, TruthEventKind.OPERATOR_BATTERY)
_EPS = 1e-9


def _window(ctx: CheckContext, drone_id: str) -> Track:
    track = ctx.window(drone_id)
    if track.empty:
        raise EvaluationError(
            f"no ground-truth samples for drone {drone_id!r} in the window "
            f"[{ctx.t0_s:g}, {ctx.t1_s:g}] s")
    return track


def _z(event_data: Mapping[str, object]) -> float:
    position = event_data["position_m"]
    return float(position[2])  # type: ignore[index]


def _drone_has_taken_off(ctx: CheckContext, p: Params) -> Outcome:
    low = p["min_altitude"] - p["tolerance"]
    high = math.inf if p["max_altitude"] is None else p["max_altitude"] + p["tolerance"]
    events = ctx.events(p["drone_id"], (TruthEventKind.TAKEOFF_COMPLETE,))
    count = sum(low <= _z(e.data) <= high for e in events)
    return Outcome(count > 0, count)


def _drone_has_landed(ctx: CheckContext, p: Params) -> Outcome:
    count = len(ctx.events(p["drone_id"], (TruthEventKind.LANDED,)))
    return Outcome(count >= p["min_count"], count)


def _drone_has_visited_position(ctx: CheckContext, p: Params) -> Outcome:
    track = _window(ctx, p["drone_id"])
    if p["z"] is None:
        points, goal = track.xy_m, np.array([p["x"], p["y"]])
    else:
        points, goal = track.xyz_m, np.array([p["x"], p["y"], p["z"]])
    offset = points - goal
    dist = np.sqrt(np.einsum("ij,ij->i", offset, offset))
    closest = float(dist.min())
    if track.size > 1:
        step = np.diff(points, axis=0)
        length = np.sqrt(np.einsum("ij,ij->i", step, step))
        # A segment is never closer than (d_start + d_end - length) / 2.
        bound = 0.5 * (dist[:-1] + dist[1:] - length)
        seg = np.flatnonzero(track.joined & (bound < closest))
        if seg.size:
            closest = min(closest, float(point_segment_distance(
                points[seg], points[seg + 1], goal).min()))
    return Outcome(closest <= p["tolerance"], round(closest, 3))


def _flown_steps(track: Track) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal displacements (dx, dy) of the joined segments."""
    d = np.diff(track.xy_m, axis=0)[track.joined] if track.size > 1 else np.zeros((0, 2))
    return d[:, 0], d[:, 1]


def _drone_has_moved_distance(ctx: CheckContext, p: Params) -> Outcome:
    dx, dy = _flown_steps(_window(ctx, p["drone_id"]))
    total = float(np.hypot(dx, dy).sum())
    return Outcome(total + _EPS >= p["min_distance"], round(total, 2))


def _drone_has_moved_directed_distance(ctx: CheckContext, p: Params) -> Outcome:
    dx, dy = _flown_steps(_window(ctx, p["drone_id"]))
    length = np.hypot(dx, dy)
    along = (length >= MIN_DIRECTED_STEP_M) & (
        heading_delta_deg(segment_bearing_deg(dx, dy), p["heading"]) <= p["tolerance"])
    total = float(length[along].sum())
    return Outcome(total + _EPS >= p["min_distance"], round(total, 2))


def hover_periods(track: Track) -> list[float]:
    """Durations of the maximal periods airborne at a speed below HOVER_MAX_SPEED_M_S."""
    if track.size < 2:
        return []
    air = track.xyz_m[:, 2] >= AIRBORNE_M
    dt = np.diff(track.t_s)
    step = np.linalg.norm(np.diff(track.xyz_m, axis=0), axis=1)
    slow = track.joined & air[:-1] & air[1:] & (step <= HOVER_MAX_SPEED_M_S * dt)
    k = np.flatnonzero(slow)
    if not k.size:
        return []
    breaks = np.flatnonzero(np.diff(k) != 1)
    firsts = np.concatenate(([k[0]], k[breaks + 1]))
    lasts = np.concatenate((k[breaks], [k[-1]]))
    return (track.t_s[lasts + 1] - track.t_s[firsts]).tolist()


def _drone_has_hovered(ctx: CheckContext, p: Params) -> Outcome:
    minimum = DEFAULT_HOVER_S if p["min_duration"] is None else p["min_duration"]
    periods = hover_periods(_window(ctx, p["drone_id"]))
    count = sum(d + _EPS >= minimum for d in periods)
    return Outcome(count >= p["min_count"], count)


def _drone_has_taken_photo(ctx: CheckContext, p: Params) -> Outcome:
    photos = ctx.events(p["drone_id"], (TruthEventKind.PHOTO,))
    where = p["at_position"]
    if where is not None:
        axes = ("x", "y", "z") if "z" in where else ("x", "y")
        goal = [where[a] for a in axes]
        photos = [e for e in photos
                  if math.dist([float(v) for v in e.data["position_m"]][:len(axes)], goal)
                  <= p["tolerance"]]
    return Outcome(len(photos) >= p["min_count"], len(photos))


def _target_in_photo_taken_by_drone(ctx: CheckContext, p: Params) -> Outcome:
    photos = ctx.events(p["drone_id"], (TruthEventKind.PHOTO,))
    count = sum(p["target_id"] in e.data.get("targets", ()) for e in photos)
    return Outcome(count > 0, count)


def _charges(ctx: CheckContext, drone_id: str) -> list[tuple[float, float]]:
    """(added amount, final battery) of every charge started in the window."""
    events = ctx.events(drone_id, (TruthEventKind.CHARGING, *CHARGE_END_EVENTS))
    out: list[tuple[float, float]] = []
    start: float | None = None
    for event in events:
        if start is not None and event.kind is not TruthEventKind.CHARGING:
            if event.kind is TruthEventKind.CHARGED:
                end = float(event.data["battery_pct"])
            else:
                end = ctx.battery_at(drone_id, event.t_s,
                                     before=event.kind is TruthEventKind.OPERATOR_BATTERY)
            out.append((end - start, end))
            start = None
        elif event.kind is TruthEventKind.CHARGING:
            if start is not None:
                end = ctx.battery_at(drone_id, event.t_s)
                out.append((end - start, end))
            raw = event.data.get("battery_pct")
            start = ctx.battery_at(drone_id, event.t_s) if raw is None else float(raw)
    if start is not None:
        end = ctx.battery_at(drone_id, ctx.t1_s)
        out.append((end - start, end))
    return out


def _drone_has_charged(ctx: CheckContext, p: Params) -> Outcome:
    minimum = p["min_charge_amount"]
    count = sum(
        end >= FULL_BATTERY_PCT or (amount > 0.0 if minimum is None else amount + _EPS >= minimum)
        for amount, end in _charges(ctx, p["drone_id"]))
    return Outcome(count > 0, count)


def _messages(ctx: CheckContext, p: Params, content: str | None) -> int:
    count = 0
    sent = (TruthEventKind.MESSAGE_SENT, TruthEventKind.MESSAGE_BROADCAST)
    for event in ctx.events(p["drone_id"], sent):
        if event.kind is TruthEventKind.MESSAGE_SENT and \
                p["to_drone_id"] not in (None, event.data.get("to")):
            continue
        if content is not None and content not in str(event.data.get("text", "")):
            continue
        count += 1
    return count


def _drone_has_sent_message(ctx: CheckContext, p: Params) -> Outcome:
    count = _messages(ctx, p, None)
    return Outcome(count >= p["min_count"], count)


def _drone_has_sent_message_content(ctx: CheckContext, p: Params) -> Outcome:
    count = _messages(ctx, p, p["content"])
    return Outcome(count >= p["min_count"], count)


def _all_drones_have_taken_off(ctx: CheckContext, p: Params) -> Outcome:
    if p["check_history"]:
        count = sum(any(_z(e.data) >= p["min_altitude"]
                        for e in ctx.events(d, (TruthEventKind.TAKEOFF_COMPLETE,)))
                    for d in ctx.drone_ids)
    else:
        count = sum(ctx.state(d).xyz_m[2] >= p["min_altitude"] for d in ctx.drone_ids)
    return Outcome(bool(ctx.drone_ids) and count == len(ctx.drone_ids), count)


def _all_drones_have_landed(ctx: CheckContext, p: Params) -> Outcome:
    if p["check_history"]:
        count = sum(len(ctx.events(d, (TruthEventKind.LANDED,))) >= p["min_count"]
                    for d in ctx.drone_ids)
    else:
        count = sum(is_on_ground(ctx.state(d), 0.1) for d in ctx.drone_ids)
    return Outcome(bool(ctx.drone_ids) and count == len(ctx.drone_ids), count)


_DRONE = entity("drone_id", "drone")
_MIN_COUNT = integer("min_count", 1, minimum=0)
_TOLERANCE_5 = number("tolerance", 5.0, minimum=0.0)
_TO_DRONE = entity("to_drone_id", "drone", None)


def _history(name: str, description: str, run: Runner, *params: ParamSpec,
             validate: Validator | None = None, ignored: frozenset[str] = frozenset()
             ) -> Endpoint:
    return Endpoint(name, "history", description, params, run, validate, ignored)


HISTORY_ENDPOINTS: tuple[Endpoint, ...] = (
    _history("drone_has_taken_off",
             "take-offs completed at an altitude within [min - tol, max + tol]",
             _drone_has_taken_off, _DRONE, number("min_altitude", 5.0),
             number("max_altitude", None), number("tolerance", 0.0, minimum=0.0),
             validate=ordered("min_altitude", "max_altitude")),
    _history("drone_has_landed", "landings >= min_count", _drone_has_landed, _DRONE,
             _MIN_COUNT, ignored=frozenset({"max_altitude"})),
    _history("drone_has_visited_position",
             "the flown trajectory passed within tolerance of (x, y[, z]); value: closest",
             _drone_has_visited_position, _DRONE, number("x"), number("y"), number("z", None),
             _TOLERANCE_5),
    _history("drone_has_moved_distance", "horizontal path length >= min_distance",
             _drone_has_moved_distance, _DRONE, number("min_distance", minimum=0.0)),
    _history("drone_has_moved_directed_distance",
             "horizontal length flown within tolerance degrees of heading >= min_distance",
             _drone_has_moved_directed_distance, _DRONE, number("min_distance", minimum=0.0),
             number("heading"), number("tolerance", 5.0, minimum=0.0, maximum=180.0)),
    _history("drone_has_hovered", "hover periods lasting >= min_duration, at least min_count",
             _drone_has_hovered, _DRONE, number("min_duration", None, minimum=0.0), _MIN_COUNT),
    _history("drone_has_taken_photo", "photos (near at_position when given) >= min_count",
             _drone_has_taken_photo, _DRONE, _MIN_COUNT, point("at_position", None),
             _TOLERANCE_5),
    _history("target_in_photo_taken_by_drone", "some photo of the drone captured the target",
             _target_in_photo_taken_by_drone, _DRONE, entity("target_id", "target")),
    _history("drone_has_charged",
             "charges adding >= min_charge_amount (> 0 when absent) or ending full",
             _drone_has_charged, _DRONE,
             number("min_charge_amount", None, minimum=0.0, maximum=100.0),
             flag("include_auto", True)),
    _history("drone_has_sent_message", "messages sent (to to_drone_id) plus broadcasts",
             _drone_has_sent_message, _DRONE, _TO_DRONE, _MIN_COUNT),
    _history("drone_has_sent_message_content",
             "messages as drone_has_sent_message whose text contains content",
             _drone_has_sent_message_content, _DRONE, text("content"), _TO_DRONE, _MIN_COUNT),
    _history("all_drones_have_taken_off",
             "every drone took off to >= min_altitude (or is there now without check_history)",
             _all_drones_have_taken_off, number("min_altitude", 5.0),
             flag("check_history", True)),
    _history("all_drones_have_landed",
             "every drone landed >= min_count times (or is on the ground without check_history)",
             _all_drones_have_landed, _MIN_COUNT, flag("check_history", True)),
)
