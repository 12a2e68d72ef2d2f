"""Current-state checks: the ground truth at the instant t1_s, the end of the task window."""

from __future__ import annotations

import itertools
import math

from benchmark.scoring.validators.context import CheckContext, DroneState
from benchmark.scoring.validators.endpoint import (
    Endpoint,
    Outcome,
    Params,
    Runner,
    Validator,
    all_of,
    different,
    ordered,
)
from benchmark.scoring.validators.geometry import Footprint, heading_delta_deg
from benchmark.scoring.validators.params import (
    REQUIRED,
    ParamSpec,
    drone_list,
    entity,
    number,
    text,
)
from benchmark.scoring.validators.reach import footprint
from mavlink_vocabulary import HOVER_SPEED_M_S

__all__ = [
    "DRONE_STATUSES",
    "HOVER_SPEED_M_S",
    "STATE_ENDPOINTS",
    "derived_status",
    "is_hovering",
    "is_on_ground",
]

# Below HOVER_SPEED_M_S (max over the last 0.05 s) an airborne drone hovers; a drone on the
# ground must also be slower than it (current speed).
DRONE_STATUSES = ("idle", "ready", "taking_off", "flying", "moving", "hovering", "landing",
                  "emergency", "offline")
_STATUS_MATCHES = {
    "idle": ("idle", "ready"),
    "hovering": ("hovering",),
    "moving": ("moving", "flying", "taking_off", "landing"),
}


def derived_status(state: DroneState) -> str:
    """idle on the ground, hovering when airborne and slow over the last second, else moving."""
    if not state.airborne:
        return "idle"
    return "hovering" if state.recent_max_speed_m_s < HOVER_SPEED_M_S else "moving"


def is_on_ground(state: DroneState, tolerance_m: float) -> bool:
    return state.xyz_m[2] <= tolerance_m and state.speed_m_s < HOVER_SPEED_M_S


def is_hovering(state: DroneState, tolerance_m: float) -> bool:
    return state.xyz_m[2] > tolerance_m and state.recent_max_speed_m_s < HOVER_SPEED_M_S


def _xy_distance(state: DroneState, x: float, y: float) -> float:
    return math.hypot(state.xyz_m[0] - x, state.xyz_m[1] - y)


def _drone_position(ctx: CheckContext, p: Params) -> Outcome:
    state = ctx.state(p["drone_id"])
    if p["z"] is None:
        dist = _xy_distance(state, p["x"], p["y"])
    else:
        dist = math.dist(state.xyz_m, (p["x"], p["y"], p["z"]))
    return Outcome(dist <= p["tolerance"], round(dist, 3))


def _drone_status(ctx: CheckContext, p: Params) -> Outcome:
    status = derived_status(ctx.state(p["drone_id"]))
    return Outcome(p["expected_status"] in _STATUS_MATCHES[status], status)


def _drone_battery_level(ctx: CheckContext, p: Params) -> Outcome:
    battery = ctx.state(p["drone_id"]).battery_pct
    return Outcome(battery >= p["min_level"], round(battery, 2))


def _drone_heading(ctx: CheckContext, p: Params) -> Outcome:
    yaw = ctx.state(p["drone_id"]).yaw_deg
    delta = float(heading_delta_deg(yaw, p["expected_heading"]))
    return Outcome(delta <= p["tolerance"], round(yaw, 2))


def _drone_over_height(ctx: CheckContext, p: Params) -> Outcome:
    z = ctx.state(p["drone_id"]).xyz_m[2]
    return Outcome(z + p["tolerance"] >= p["min_height"], round(z, 3))


def _drone_altitude(ctx: CheckContext, p: Params) -> Outcome:
    z = ctx.state(p["drone_id"]).xyz_m[2]
    return Outcome(abs(z - p["expected_altitude"]) <= p["tolerance"], round(z, 3))


def _drone_on_ground(ctx: CheckContext, p: Params) -> Outcome:
    state = ctx.state(p["drone_id"])
    return Outcome(is_on_ground(state, p["tolerance"]), round(state.xyz_m[2], 3))


def _drone_hovering(ctx: CheckContext, p: Params) -> Outcome:
    state = ctx.state(p["drone_id"])
    return Outcome(is_hovering(state, p["tolerance"]), round(state.recent_max_speed_m_s, 3))


def _all_drones_on_ground(ctx: CheckContext, p: Params) -> Outcome:
    count = sum(is_on_ground(ctx.state(d), p["tolerance"]) for d in ctx.drone_ids)
    return Outcome(bool(ctx.drone_ids) and count == len(ctx.drone_ids), count)


def _all_drones_hovering(ctx: CheckContext, p: Params) -> Outcome:
    count = sum(is_hovering(ctx.state(d), p["tolerance"]) for d in ctx.drone_ids)
    return Outcome(bool(ctx.drone_ids) and count == len(ctx.drone_ids), count)


def _drone_at_home(ctx: CheckContext, p: Params) -> Outcome:
    home = ctx.home_at(p["drone_id"], ctx.t1_s)
    dist = _xy_distance(ctx.state(p["drone_id"]), home[0], home[1])
    return Outcome(dist <= p["tolerance"], round(dist, 3))


def _target_distance(ctx: CheckContext, p: Params) -> float:
    x, y, _ = ctx.state(p["drone_id"]).xyz_m
    return footprint(ctx, p["target_id"]).distance_xy(x, y)


def _drone_in_target(ctx: CheckContext, p: Params) -> Outcome:
    dist = _target_distance(ctx, p)
    return Outcome(dist <= 1e-9, round(dist, 3))


def _target_within_distance(ctx: CheckContext, p: Params) -> Outcome:
    dist = _target_distance(ctx, p)
    return Outcome(dist <= p["max_distance"], round(dist, 3))


def _target_within_task_radius(ctx: CheckContext, p: Params) -> Outcome:
    dist = _target_distance(ctx, p)
    return Outcome(dist <= ctx.vehicle(p["drone_id"]).task_radius_m, round(dist, 3))


def _target_within_perceived_radius(ctx: CheckContext, p: Params) -> Outcome:
    dist = _target_distance(ctx, p)
    return Outcome(dist <= ctx.vehicle(p["drone_id"]).perceived_radius_m, round(dist, 3))


def _obstacle_distance(ctx: CheckContext, p: Params) -> float:
    x, y, _ = ctx.state(p["drone_id"]).xyz_m
    shape = ctx.cached(("obstacle", p["obstacle_id"]),
                       lambda: Footprint.of_obstacle(ctx.obstacle(p["obstacle_id"])))
    return shape.distance_xy(x, y)


def _obstacle_within_distance(ctx: CheckContext, p: Params) -> Outcome:
    dist = _obstacle_distance(ctx, p)
    return Outcome(dist <= p["max_distance"], round(dist, 3))


def _obstacle_within_perceived_radius(ctx: CheckContext, p: Params) -> Outcome:
    dist = _obstacle_distance(ctx, p)
    return Outcome(dist <= ctx.vehicle(p["drone_id"]).perceived_radius_m, round(dist, 3))


def _pair_ok(dist: float, p: Params) -> bool:
    return p["min_distance"] <= dist and (p["max_distance"] is None or dist <= p["max_distance"])


def _two_drones_distance(ctx: CheckContext, p: Params) -> Outcome:
    dist = math.dist(ctx.state(p["drone_1_id"]).xyz_m, ctx.state(p["drone_2_id"]).xyz_m)
    return Outcome(_pair_ok(dist, p), round(dist, 3))


def _drone_group_distance(ctx: CheckContext, p: Params) -> Outcome:
    positions = [ctx.state(d).xyz_m for d in p["drone_ids"]]
    passing = sum(_pair_ok(math.dist(a, b), p) for a, b in itertools.combinations(positions, 2))
    pairs = len(positions) * (len(positions) - 1) // 2
    result = passing == pairs if p["mode"] == "all_pairs" else passing > 0
    return Outcome(result, passing)


_DRONE = entity("drone_id", "drone")
_TARGET = entity("target_id", "target")
_OBSTACLE = entity("obstacle_id", "obstacle")


def _tolerance(default: float, maximum: float | None = None) -> ParamSpec:
    return number("tolerance", default, minimum=0.0, maximum=maximum)


def _max_distance(default: object = None) -> ParamSpec:
    return number("max_distance", default, minimum=0.0)


_MIN_DISTANCE = number("min_distance", 0.0, minimum=0.0)


def _state(name: str, description: str, run: Runner, *params: ParamSpec,
           validate: Validator | None = None) -> Endpoint:
    return Endpoint(name, "state", description, params, run, validate)


STATE_ENDPOINTS: tuple[Endpoint, ...] = (
    _state("drone_position", "distance to (x, y[, z]) <= tolerance; 3D when z is given",
           _drone_position, _DRONE, number("x"), number("y"), number("z", None),
           _tolerance(1.0)),
    _state("drone_status", "derived status (idle, hovering or moving) matches expected_status",
           _drone_status, _DRONE, text("expected_status", choices=DRONE_STATUSES)),
    _state("drone_battery_level", "battery percentage >= min_level", _drone_battery_level,
           _DRONE, number("min_level", 0.0, minimum=0.0, maximum=100.0)),
    _state("drone_heading", "heading within tolerance degrees of expected_heading",
           _drone_heading, _DRONE, number("expected_heading"), _tolerance(5.0, 180.0)),
    _state("drone_over_height", "z + tolerance >= min_height", _drone_over_height, _DRONE,
           number("min_height"), _tolerance(0.1)),
    _state("drone_altitude", "|z - expected_altitude| <= tolerance", _drone_altitude, _DRONE,
           number("expected_altitude"), _tolerance(0.5)),
    _state("drone_on_ground", f"z <= tolerance and speed < {HOVER_SPEED_M_S} m/s",
           _drone_on_ground, _DRONE, _tolerance(0.1)),
    _state("drone_hovering",
           f"z > tolerance and max speed over the last 0.05 s < {HOVER_SPEED_M_S} m/s",
           _drone_hovering, _DRONE, _tolerance(0.1)),
    _state("all_drones_on_ground", "every drone is on the ground (false without drones)",
           _all_drones_on_ground, _tolerance(0.1)),
    _state("all_drones_hovering", "every drone hovers (false without drones)",
           _all_drones_hovering, _tolerance(0.1)),
    _state("drone_at_home", "2D distance to the current home <= tolerance", _drone_at_home,
           _DRONE, _tolerance(1.0)),
    _state("drone_in_target", "drone (x, y) inside the target footprint", _drone_in_target,
           _DRONE, _TARGET),
    _state("target_within_drone_distance", "2D distance to the footprint <= max_distance",
           _target_within_distance, _DRONE, _TARGET, _max_distance(REQUIRED)),
    _state("target_within_drone_task_radius",
           "2D distance to the footprint <= the drone's task radius",
           _target_within_task_radius, _DRONE, _TARGET),
    _state("target_within_drone_perceived_radius",
           "2D distance to the footprint <= the drone's perceived radius",
           _target_within_perceived_radius, _DRONE, _TARGET),
    _state("obstacle_within_drone_distance",
           "2D distance to the obstacle footprint <= max_distance",
           _obstacle_within_distance, _DRONE, _OBSTACLE, _max_distance(REQUIRED)),
    _state("obstacle_within_drone_perceived_radius",
           "2D distance to the obstacle footprint <= the drone's perceived radius",
           _obstacle_within_perceived_radius, _DRONE, _OBSTACLE),
    _state("two_drones_distance", "min_distance <= 3D distance <= max_distance (if given)",
           _two_drones_distance, entity("drone_1_id", "drone"), entity("drone_2_id", "drone"),
           _max_distance(), _MIN_DISTANCE,
           validate=all_of(different("drone_1_id", "drone_2_id"),
                           ordered("min_distance", "max_distance"))),
    _state("drone_group_distance",
           "pairs within [min_distance, max_distance]: all pairs or any pair (mode)",
           _drone_group_distance, drone_list("drone_ids"), _max_distance(), _MIN_DISTANCE,
           text("mode", "all_pairs", choices=("all_pairs", "any_pair")),
           validate=ordered("min_distance", "max_distance")),
)
