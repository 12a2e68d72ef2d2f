"""A plan derived from a task's check tree: what the oracle flies when a task has no hand-written
plan (or when hand plans are turned off).

The tree is read leaf by leaf (an ``or`` group by one branch: the first whose drones no hidden
fault strikes). Every leaf adds to one drone's intentions: a take-off altitude, an ordered list
of actions (visit, reach, photograph, hover, directed legs, messages, charging, tracking and
intercepting moving targets), a share of a team job (covering an area, reaching targets) or a
wish for the end state (where, how high, on the ground or in the air, facing where, at home,
near whom). The intentions become a three-phase plan in the operations of
`benchmark.authoring.templates.base`: (1) take-offs and each drone's actions in the tree's order,
(2) team jobs, (3) end states. A leaf the planner cannot satisfy raises `Unplannable`, which
names the leaf's path, its endpoint and the reason.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

from benchmark.scoring.validators.tree import Leaf, Node
from emulator.scenario import Scenario
from swarm_agents.oracle.intentions import DroneIntent, Intentions, Unplannable, target_point

__all__ = ["Unplannable", "derive_plan", "plannable_endpoints"]

Op = dict[str, Any]
Params = Mapping[str, Any]
Handler = Callable[[Intentions, str, Params, bool], None]

HOVER_EXTRA_S = 2.0
TRACK_EXTRA_S = 6.0
DIRECTED_SHARE = 1.1  # a directed leg flies this multiple of the distance asked (+ 1 m)


def _drone(it: Intentions, path: str, p: Params) -> DroneIntent:
    return it.drone(p["drone_id"], path)


# ------------------------------------------------------------------ handlers: positions
def _visited(it: Intentions, path: str, p: Params, expect: bool) -> None:
    z = p.get("z")
    _drone(it, path, p).visit(float(p["x"]), float(p["y"]), None if z is None else float(z))


def _position(it: Intentions, path: str, p: Params, expect: bool) -> None:
    d = _drone(it, path, p)
    d.final_xy = (float(p["x"]), float(p["y"]))
    if p.get("z") is not None:
        d.final_z = float(p["z"])


def _at_home(it: Intentions, path: str, p: Params, expect: bool) -> None:
    _drone(it, path, p).final_home = True


def _on_ground(it: Intentions, path: str, p: Params, expect: bool) -> None:
    d = _drone(it, path, p)
    if expect:
        d.final_ground = True
    else:
        d.must_air = True


def _all_on_ground(it: Intentions, path: str, p: Params, expect: bool) -> None:
    for d in it.all_drones():
        d.final_ground = True


def _hovering(it: Intentions, path: str, p: Params, expect: bool) -> None:
    d = _drone(it, path, p)
    if expect:
        d.must_air = True
    else:  # not hovering: on the ground is the still way
        d.final_ground = True


def _all_hovering(it: Intentions, path: str, p: Params, expect: bool) -> None:
    for d in it.all_drones():
        d.must_air = True


def _status(it: Intentions, path: str, p: Params, expect: bool) -> None:
    d = _drone(it, path, p)
    status = p["expected_status"]
    if status == "idle":
        d.final_ground = True
    elif status == "hovering":
        d.must_air = True
    else:
        raise Unplannable(path, "drone_status", f"cannot end the task with the drone {status}")


def _altitude(it: Intentions, path: str, p: Params, expect: bool) -> None:
    d = _drone(it, path, p)
    d.must_air = True
    d.final_alt = float(p["expected_altitude"])


def _over_height(it: Intentions, path: str, p: Params, expect: bool) -> None:
    d = _drone(it, path, p)
    d.must_air = True
    d.min_final_alt = max(d.min_final_alt, float(p["min_height"]) + 1.0)


def _heading(it: Intentions, path: str, p: Params, expect: bool) -> None:
    d = _drone(it, path, p)
    d.must_air = True
    d.final_heading = float(p["expected_heading"])


def _battery(it: Intentions, path: str, p: Params, expect: bool) -> None:
    d = _drone(it, path, p)
    d.min_battery = max(d.min_battery, float(p["min_level"]))


def _in_target(it: Intentions, path: str, p: Params, expect: bool) -> None:
    d = _drone(it, path, p)
    target = it.target(p["target_id"], path)
    if target.is_moving:
        raise Unplannable(path, "drone_in_target", "cannot end the task inside a moving target")
    if target.is_charging_station:
        d.end_station = target.id
    else:
        d.final_xy = target_point(target)


def _near_target(endpoint: str) -> Handler:
    def handle(it: Intentions, path: str, p: Params, expect: bool) -> None:
        d = _drone(it, path, p)
        target = it.target(p["target_id"], path)
        if target.is_moving:
            raise Unplannable(path, endpoint, "cannot end the task beside a moving target")
        d.final_xy = target_point(target)
    return handle


def _near_obstacle(endpoint: str) -> Handler:
    def handle(it: Intentions, path: str, p: Params, expect: bool) -> None:
        d = _drone(it, path, p)
        limit = p.get("max_distance")
        if limit is None:
            limit = it.vehicle(d.id).perceived_radius_m
        d.final_xy, d.final_z = it.beside_obstacle(p["obstacle_id"], float(limit), path,
                                                   endpoint)
    return handle


def _pair(it: Intentions, path: str, p: Params, expect: bool) -> None:
    it.spacing.append((path, [p["drone_1_id"], p["drone_2_id"]], float(p["min_distance"]),
                       p.get("max_distance"), "all_pairs"))


def _group(it: Intentions, path: str, p: Params, expect: bool) -> None:
    it.spacing.append((path, list(p["drone_ids"]), float(p["min_distance"]),
                       p.get("max_distance"), p["mode"]))


# ------------------------------------------------------------------ handlers: history
def _taken_off(it: Intentions, path: str, p: Params, expect: bool) -> None:
    d = _drone(it, path, p)
    hi = p.get("max_altitude")
    d.takeoff_range = (float(p["min_altitude"]), None if hi is None else float(hi))


def _all_taken_off(it: Intentions, path: str, p: Params, expect: bool) -> None:
    for d in it.all_drones():
        if d.takeoff_range is None:
            d.takeoff_range = (float(p["min_altitude"]) + 1.0, None)


def _landed(it: Intentions, path: str, p: Params, expect: bool) -> None:
    d = _drone(it, path, p)
    d.min_landings = max(d.min_landings, int(p["min_count"]))


def _all_landed(it: Intentions, path: str, p: Params, expect: bool) -> None:
    for d in it.all_drones():
        d.min_landings = max(d.min_landings, int(p["min_count"]))


def _moved(it: Intentions, path: str, p: Params, expect: bool) -> None:
    d = _drone(it, path, p)
    d.min_path_m = max(d.min_path_m, float(p["min_distance"]))


def _directed(it: Intentions, path: str, p: Params, expect: bool) -> None:
    distance = DIRECTED_SHARE * float(p["min_distance"]) + 1.0
    _drone(it, path, p).act({"op": "towards", "heading_deg": float(p["heading"]),
                             "distance_m": round(distance, 1)})


def _hovered(it: Intentions, path: str, p: Params, expect: bool) -> None:
    d = _drone(it, path, p)
    duration = float(p.get("min_duration") or 1.0) + HOVER_EXTRA_S
    for k in range(int(p["min_count"])):
        if k:  # a separate hover period: move off the spot and back between them
            d.act({"op": "towards", "heading_deg": 0.0, "distance_m": 4.0})
        d.act({"op": "hover", "duration_s": duration})


def _photo(it: Intentions, path: str, p: Params, expect: bool) -> None:
    d = _drone(it, path, p)
    at = p.get("at_position")
    if at is None:
        d.min_photos = max(d.min_photos, int(p["min_count"]))
        return
    d.visit(float(at["x"]), float(at["y"]), None if at.get("z") is None else float(at["z"]))
    for _ in range(int(p["min_count"])):  # every photo counted must be taken there
        d.act({"op": "photo"})


def _photo_of(it: Intentions, path: str, p: Params, expect: bool) -> None:
    d = _drone(it, path, p)
    target = it.target(p["target_id"], path)
    if target.is_moving:
        d.act({"op": "photo_target", "target": target.id})
    else:
        d.photograph(target.id)


def _charged(it: Intentions, path: str, p: Params, expect: bool) -> None:
    _drone(it, path, p).charge_path = path


def _message(it: Intentions, path: str, p: Params, expect: bool) -> None:
    d = _drone(it, path, p)
    text = str(p.get("content") or f"{d.id} reporting: task under way")
    to = p.get("to_drone_id")
    for _ in range(int(p["min_count"])):
        d.act({"op": "message", "to": to, "text": text} if to else
              {"op": "broadcast", "text": text})


# ------------------------------------------------------------------ handlers: targets
def _reached_by(it: Intentions, path: str, p: Params, expect: bool) -> None:
    _drone(it, path, p).reach(it.target(p["target_id"], path).id)


def _reached_any(it: Intentions, path: str, p: Params, expect: bool) -> None:
    it.reach_any.append((path, it.target(p["target_id"], path).id, 1))


def _reached_count(it: Intentions, path: str, p: Params, expect: bool) -> None:
    count = p.get("expected_count") or 1
    it.reach_any.append((path, it.target(p["target_id"], path).id, int(count)))


def _tracked(it: Intentions, path: str, p: Params, expect: bool) -> None:
    target = it.target(p["target_id"], path)
    if not target.is_moving:
        it.reach_any.append((path, target.id, 1))
        return
    duration = float(p["min_duration"]) + TRACK_EXTRA_S
    it.tracks.append((path, target.id, p.get("drone_id"), duration))


def _in_zone(it: Intentions, path: str, p: Params, expect: bool) -> None:
    _drone(it, path, p).act({"op": "intercept", "target": p["target_id"],
                             "zone": [float(p["x"]), float(p["y"]), float(p["radius"])]})


def _searched(key: str) -> Handler:
    def handle(it: Intentions, path: str, p: Params, expect: bool) -> None:
        it.sweep_target(path, p["target_id"], float(p[key]))
    return handle


def _progress(it: Intentions, path: str, p: Params, expect: bool) -> None:
    it.whole_task(path)


HANDLERS: dict[str, Handler] = {
    "drone_position": _position,
    "drone_status": _status,
    "drone_battery_level": _battery,
    "drone_heading": _heading,
    "drone_over_height": _over_height,
    "drone_altitude": _altitude,
    "drone_on_ground": _on_ground,
    "drone_hovering": _hovering,
    "all_drones_on_ground": _all_on_ground,
    "all_drones_hovering": _all_hovering,
    "drone_at_home": _at_home,
    "drone_in_target": _in_target,
    "target_within_drone_distance": _near_target("target_within_drone_distance"),
    "target_within_drone_task_radius": _near_target("target_within_drone_task_radius"),
    "target_within_drone_perceived_radius": _near_target(
        "target_within_drone_perceived_radius"),
    "obstacle_within_drone_distance": _near_obstacle("obstacle_within_drone_distance"),
    "obstacle_within_drone_perceived_radius": _near_obstacle(
        "obstacle_within_drone_perceived_radius"),
    "two_drones_distance": _pair,
    "drone_group_distance": _group,
    "target_is_reached": _reached_any,
    "target_is_reached_by_drone": _reached_by,
    "target_reached_drone_number": _reached_count,
    "moving_target_tracked": _tracked,
    "moving_target_reached_in_zone": _in_zone,
    "target_is_fully_searched": _searched("coverage_threshold"),
    "target_searched_area_percentage": _searched("expected_percentage"),
    "task_progress": _progress,
    "task_done": _progress,
    "drone_has_taken_off": _taken_off,
    "drone_has_landed": _landed,
    "drone_has_visited_position": _visited,
    "drone_has_moved_distance": _moved,
    "drone_has_moved_directed_distance": _directed,
    "drone_has_hovered": _hovered,
    "drone_has_taken_photo": _photo,
    "target_in_photo_taken_by_drone": _photo_of,
    "drone_has_charged": _charged,
    "drone_has_sent_message": _message,
    "drone_has_sent_message_content": _message,
    "all_drones_have_taken_off": _all_taken_off,
    "all_drones_have_landed": _all_landed,
}

# A negated leaf of these holds as long as the plan does not act for it.
PASSIVE_WHEN_NEGATED = frozenset(name for name in HANDLERS if name.startswith((
    "drone_has_", "target_is_", "target_in_photo", "target_reached", "moving_target",
    "all_drones_have", "task_")))


# A negated leaf of these has a plan of its own (the handler reads expect).
NEGATABLE = frozenset({"drone_on_ground", "drone_hovering"})


def plannable_endpoints() -> list[str]:
    """Every endpoint the planner has a rule for."""
    return sorted(HANDLERS)


# ------------------------------------------------------------------ the tree
def _drones_of(node: Node) -> set[str]:
    if isinstance(node, Leaf):
        found: set[str] = set()
        for key, value in node.parameters.items():
            if key in ("drone_id", "drone_1_id", "drone_2_id", "to_drone_id") and value:
                found.add(str(value))
            elif key == "drone_ids":
                found.update(str(v) for v in value)
        return found
    out: set[str] = set()
    for child in node.checks:
        out |= _drones_of(child)
    return out


def _leaves(node: Node, path: str, negate: bool, faulted: set[str]
            ) -> list[tuple[str, Leaf, bool]]:
    """The leaves the plan must satisfy, with their paths and whether each must hold."""
    if isinstance(node, Leaf):
        return [(path, node, node.expect != negate)]
    if node.logic == "not":
        if len(node.checks) != 1:
            raise Unplannable(path, "not", "a 'not' group of several checks has no plan")
        return _leaves(node.checks[0], f"{path}[0]", not negate, faulted)
    if (node.logic == "or") != negate:  # or, or not(and): one branch must hold
        if not node.checks:
            raise Unplannable(path, node.logic, "an empty group that must hold cannot")
        order = sorted(range(len(node.checks)),
                       key=lambda k: bool(_drones_of(node.checks[k]) & faulted))
        error: Unplannable | None = None
        for k in order:
            try:
                return _leaves(node.checks[k], f"{path}[{k}]", negate, faulted)
            except Unplannable as exc:
                error = error or exc
        assert error is not None
        raise error
    out: list[tuple[str, Leaf, bool]] = []
    for k, child in enumerate(node.checks):
        out.extend(_leaves(child, f"{path}[{k}]", negate, faulted))
    return out


def derive_plan(checks: Node, scenario: Scenario, drones: Mapping[str, Mapping[str, Any]],
                *, faulted: Sequence[str] = ()) -> list[list[Op]]:
    """The plan for `checks`, from the drones' current states (list_drones rows by id);
    drones in `faulted` are struck by a hidden fault and given no optional work."""
    failing = set(faulted)
    it = Intentions(scenario, drones, failing, _drones_of(checks))
    leaves = _leaves(checks, "checks", False, failing)
    for path, leaf, holds in leaves:
        handler = HANDLERS.get(leaf.endpoint)
        if handler is None:
            raise Unplannable(path, leaf.endpoint, "no planning rule for this endpoint")
        if not holds:
            if leaf.endpoint in PASSIVE_WHEN_NEGATED:
                continue
            if leaf.endpoint not in NEGATABLE:
                raise Unplannable(path, leaf.endpoint, "cannot plan for this check to fail")
        handler(it, path, leaf.parameters, holds)
    return it.plan()

