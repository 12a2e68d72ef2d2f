"""The oracle's derived planner: plans made from check trees alone, flown through the emulator
on worlds drawn by Hypothesis (derandomized), one group of endpoints per test; a leaf it cannot
plan ends the task with a record naming the leaf and the reason."""

from __future__ import annotations

import asyncio
import math
from typing import Any

import pytest
import shapely
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from benchmark.authoring.session_file import session_from_dict
from benchmark.running.episode import run_one_task
from benchmark.scoring.validators import ENDPOINTS, parse_tree
from swarm_agents.oracle import OracleAgent
from swarm_agents.oracle.derive import Unplannable, derive_plan, plannable_endpoints
from swarm_agents.oracle.pursuit import Pursuit
from swarm_agents.oracle.session_oracle import oracle_for_session

FLIGHTS = settings(derandomize=True, database=None, deadline=None, max_examples=3,
                   phases=(Phase.explicit, Phase.generate),
                   suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
MAP_M = 400.0
BASE = (40.0, 40.0)


def _leaf(endpoint: str, **parameters: Any) -> dict[str, Any]:
    return {"endpoint": endpoint, "parameters": parameters}


def _xy(x: float, y: float) -> dict[str, float]:
    return {"x": x, "y": y, "z": 0.0}


@st.composite
def worlds(draw: st.DrawFn, task_type: str = "others") -> dict[str, Any]:
    """A 400 m map: three drones at a base in the southwest corner, one to three obstacles
    (walls to the sky or low blocks), a point target, an area, a charging station and a
    moving target, none of them overlapping an obstacle."""
    obstacles: list[dict[str, Any]] = []
    shapes: list[shapely.Geometry] = []
    for k in range(draw(st.integers(1, 3))):
        x, y = draw(st.integers(120, 330)), draw(st.integers(120, 330))
        radius = draw(st.integers(8, 20))
        height = draw(st.sampled_from([0.0, 12.0]))
        obstacles.append({"id": f"o{k + 1}", "name": f"Block {k + 1}", "type": "circle",
                          "position": _xy(x, y), "radius": radius, "height": height})
        shapes.append(shapely.Point(x, y).buffer(radius + 25.0))
    blocked = shapely.union_all(shapes)

    def free_xy(lo: int, hi: int) -> tuple[float, float]:
        spot = draw(st.tuples(st.integers(lo, hi), st.integers(lo, hi)).filter(
            lambda p: not blocked.contains(shapely.Point(p))))
        return float(spot[0]), float(spot[1])

    point, area, station, mover = (free_xy(80, 340) for _ in range(4))
    angle = draw(st.floats(0.0, 2.0 * math.pi))
    targets = [
        {"id": "t1", "name": "Target 1", "type": "fixed", "position": _xy(*point), "radius": 3},
        {"id": "t2", "name": "Area 1", "type": "circle", "position": _xy(*area),
         "radius": draw(st.integers(15, 30))},
        {"id": "t3", "name": "Charging Station 1", "type": "waypoint",
         "position": _xy(*station), "radius": 8, "charge_amount": 40.0},
        {"id": "t4", "name": "Moving Target 1", "type": "moving", "position": _xy(*mover),
         "radius": 5, "velocity": {"x": round(1.5 * math.cos(angle), 2),
                                   "y": round(1.5 * math.sin(angle), 2), "z": 0.0},
         "moving_duration": 20.0},
    ]
    drones = [{"id": f"d{k + 1}", "name": f"Drone {k + 1}", "model": "MS-Quad",
               "position": _xy(BASE[0] + 10 * k, BASE[1]), "heading": 0.0,
               "home_position": _xy(BASE[0] + 10 * k, BASE[1]), "max_speed": 15,
               "max_altitude": 120, "perceived_radius": 50, "task_radius": 20,
               "battery_level": 100.0, "battery_capacity": 5000.0} for k in range(3)]
    return {"schema": "mavswarm.session/1", "id": "drawn", "family": "drawn", "level": "easy",
            "index": 1, "seed": 1, "name": "drawn", "description": "", "task_type": task_type,
            "map_size_m": [MAP_M, MAP_M], "safety_margin_m": 2.0, "drones": drones,
            "targets": targets, "obstacles": obstacles, "tasks": [],
            "points": [free_xy(60, 340) for _ in range(4)]}


def _fly(world: dict[str, Any], checks: Any, sim_time_s: float = 900.0) -> dict[str, Any]:
    """One task with these checks and no hand plan, flown by the oracle (derived plans)."""
    data = {k: v for k, v in world.items() if k != "points"}
    data["tasks"] = [{"id": "t01", "template": "drawn", "category": "basic_operations",
                      "difficulty": "easy", "text": "Do what the checks ask.",
                      "budget": {"tool_calls": 400, "sim_time_s": sim_time_s},
                      "checks": checks, "oracle": None}]
    session = session_from_dict(data, source="drawn")
    assert session.tasks[0].error is None, session.tasks[0].error
    agent = oracle_for_session(session, mode="derived")
    return asyncio.run(run_one_task(session, session.tasks[0], agent))


def _passed(record: dict[str, Any]) -> None:
    failed = [(c["endpoint"], c.get("value")) for c in record["checks"] if not c["passed"]]
    assert record["passed"], (record["finish"], record["error"], failed)
    assert record["tool_calls"] > 0


def test_every_endpoint_has_a_planning_rule() -> None:
    assert plannable_endpoints() == sorted(ENDPOINTS)


@pytest.mark.slow  # flies episodes: seconds each
@FLIGHTS
@given(worlds(), st.integers(12, 30), st.integers(0, 359))
def test_positions_photos_hover_heading(world: dict[str, Any], alt: int, heading: int) -> None:
    p1, p2, p3, _ = world["points"]
    checks = [
        _leaf("drone_has_visited_position", drone_id="d1", x=p1[0], y=p1[1], z=alt,
              tolerance=3.0),
        _leaf("drone_has_taken_photo", drone_id="d1", min_count=2,
              at_position={"x": p2[0], "y": p2[1]}),
        _leaf("drone_has_hovered", drone_id="d1", min_duration=6.0),
        _leaf("drone_position", drone_id="d1", x=p3[0], y=p3[1], z=alt, tolerance=3.0),
        _leaf("drone_altitude", drone_id="d1", expected_altitude=alt, tolerance=2.0),
        _leaf("drone_heading", drone_id="d1", expected_heading=heading),
        _leaf("drone_hovering", drone_id="d1", tolerance=0.5),
        _leaf("drone_over_height", drone_id="d1", min_height=alt - 5),
        _leaf("drone_status", drone_id="d3", expected_status="idle"),
    ]
    _passed(_fly(world, checks))


@pytest.mark.slow  # flies episodes: seconds each
@FLIGHTS
@given(worlds(), st.integers(12, 25), st.integers(0, 3))
def test_takeoff_landings_home_distances(world: dict[str, Any], alt: int, quarter: int) -> None:
    p1, p2, _, _ = world["points"]
    checks = [
        _leaf("drone_has_taken_off", drone_id="d2", min_altitude=alt, max_altitude=alt,
              tolerance=1.5),
        _leaf("drone_has_visited_position", drone_id="d2", x=p1[0], y=p1[1], z=0.0,
              tolerance=3.0),
        _leaf("drone_has_landed", drone_id="d2", min_count=3),
        _leaf("drone_has_moved_distance", drone_id="d2", min_distance=600.0),
        _leaf("drone_at_home", drone_id="d2", tolerance=3.0),
        _leaf("drone_on_ground", drone_id="d2", tolerance=0.5),
        _leaf("drone_battery_level", drone_id="d2", min_level=20.0),
        _leaf("drone_has_visited_position", drone_id="d1", x=p2[0], y=p2[1], tolerance=3.0),
        _leaf("drone_has_moved_directed_distance", drone_id="d1", min_distance=40.0,
              heading=90.0 * quarter),
    ]
    _passed(_fly(world, checks))


@pytest.mark.slow  # flies episodes: seconds each
@FLIGHTS
@given(worlds())
def test_targets_photos_and_coverage(world: dict[str, Any]) -> None:
    checks = [
        _leaf("target_is_reached_by_drone", target_id="t1", drone_id="d1"),
        _leaf("target_in_photo_taken_by_drone", drone_id="d2", target_id="t1"),
        _leaf("target_reached_drone_number", target_id="t1", expected_count=2),
        _leaf("target_is_reached", target_id="t2"),
        _leaf("target_is_fully_searched", target_id="t2", coverage_threshold=0.95),
        _leaf("target_searched_area_percentage", target_id="t2", expected_percentage=0.9),
        _leaf("target_within_drone_distance", drone_id="d3", target_id="t1", max_distance=5.0),
        _leaf("target_within_drone_task_radius", drone_id="d3", target_id="t1"),
        _leaf("target_within_drone_perceived_radius", drone_id="d3", target_id="t1"),
        _leaf("drone_in_target", drone_id="d1", target_id="t2"),
        _leaf("obstacle_within_drone_perceived_radius", drone_id="d2", obstacle_id="o1"),
        _leaf("obstacle_within_drone_distance", drone_id="d2", obstacle_id="o1",
              max_distance=10.0),
    ]
    _passed(_fly(world, checks))


@pytest.mark.slow  # flies episodes: seconds each
@FLIGHTS
@given(worlds(), st.integers(15, 30))
def test_team_spacing_and_messages(world: dict[str, Any], alt: int) -> None:
    p1, _, _, _ = world["points"]
    checks = [
        _leaf("all_drones_have_taken_off", min_altitude=alt),
        _leaf("drone_has_visited_position", drone_id="d1", x=p1[0], y=p1[1], z=alt,
              tolerance=3.0),
        _leaf("two_drones_distance", drone_1_id="d1", drone_2_id="d2", max_distance=25.0,
              min_distance=8.0),
        _leaf("drone_group_distance", drone_ids=["d1", "d2", "d3"], max_distance=40.0),
        _leaf("all_drones_hovering", tolerance=0.5),
        _leaf("drone_has_sent_message_content", drone_id="d1", to_drone_id="d2",
              content="ALPHA-7", min_count=2),
        _leaf("drone_has_sent_message", drone_id="d3", min_count=1),
        {"logic": "not", "checks": [_leaf("drone_on_ground", drone_id="d3", tolerance=0.5)]},
    ]
    _passed(_fly(world, checks))


@pytest.mark.slow  # flies episodes: seconds each
@FLIGHTS
@given(worlds())
def test_charging_and_landing_everyone(world: dict[str, Any]) -> None:
    p1, _, _, _ = world["points"]
    checks = [
        _leaf("drone_has_visited_position", drone_id="d1", x=p1[0], y=p1[1], tolerance=3.0),
        _leaf("drone_has_charged", drone_id="d1"),
        _leaf("drone_battery_level", drone_id="d1", min_level=99.0),
        _leaf("drone_in_target", drone_id="d1", target_id="t3"),
        _leaf("drone_on_ground", drone_id="d1", tolerance=0.5),
        _leaf("all_drones_have_landed", min_count=1),
        _leaf("all_drones_on_ground"),
        {"logic": "not", "checks": [_leaf("drone_hovering", drone_id="d2")]},
    ]
    _passed(_fly(world, checks))


@pytest.mark.slow  # flies episodes: seconds each
@FLIGHTS
@given(worlds(), st.integers(40, 90))
def test_moving_target(world: dict[str, Any], zone_at_s: int) -> None:
    scenario = session_from_dict({k: v for k, v in world.items() if k != "points"}).scenario
    x, y = Pursuit(scenario.world).xy("t4", float(zone_at_s))
    checks = [
        _leaf("moving_target_tracked", target_id="t4", drone_id="d1", min_duration=20.0),
        _leaf("target_in_photo_taken_by_drone", drone_id="d2", target_id="t4"),
        _leaf("moving_target_reached_in_zone", target_id="t4", drone_id="d3", x=round(x, 1),
              y=round(y, 1), radius=15.0),
        _leaf("target_is_reached", target_id="t4"),
    ]
    _passed(_fly(world, checks))


@pytest.mark.slow  # flies episodes: seconds each
@FLIGHTS
@given(worlds(task_type="target_assignment"))
def test_task_progress_of_the_session(world: dict[str, Any]) -> None:
    world = {**world, "targets": [t for t in world["targets"] if t["type"] != "moving"]}
    _passed(_fly(world, [_leaf("task_progress", expected_progress=1.0), _leaf("task_done")]))


def test_an_or_group_avoids_the_drone_a_fault_strikes() -> None:
    data = _fixed_world()
    checks = parse_tree({"logic": "or", "checks": [
        _leaf("drone_has_visited_position", drone_id="d1", x=200.0, y=60.0, tolerance=3.0),
        _leaf("drone_has_visited_position", drone_id="d2", x=200.0, y=60.0, tolerance=3.0)]},
        session_from_dict(data).scenario)
    scenario = session_from_dict(data).scenario
    plan = derive_plan(checks, scenario, {}, faulted=["d1"])
    drones = {op["drone"] for phase in plan for op in phase}
    assert drones == {"d2"}
    plan = derive_plan(checks, scenario, {})
    assert {op["drone"] for phase in plan for op in phase} == {"d1"}


def _fixed_world() -> dict[str, Any]:
    drones = [{"id": f"d{k + 1}", "name": f"Drone {k + 1}", "model": "MS-Quad",
               "position": _xy(40 + 10 * k, 40), "heading": 0.0,
               "home_position": _xy(40 + 10 * k, 40), "max_speed": 15, "max_altitude": 120,
               "perceived_radius": 50, "task_radius": 20, "battery_level": 100.0,
               "battery_capacity": 5000.0} for k in range(2)]
    return {"schema": "mavswarm.session/1", "id": "fixed", "family": "drawn", "level": "easy",
            "index": 1, "seed": 1, "name": "fixed", "description": "", "task_type": "others",
            "map_size_m": [MAP_M, MAP_M], "safety_margin_m": 2.0, "drones": drones,
            "targets": [{"id": "t1", "name": "Target 1", "type": "fixed",
                         "position": _xy(300, 300), "radius": 3}],
            "obstacles": [], "tasks": []}


@pytest.mark.parametrize(("checks", "path", "endpoint"), [
    (_leaf("drone_status", drone_id="d1", expected_status="moving"), "checks", "drone_status"),
    ([_leaf("drone_has_landed", drone_id="d1"),
      _leaf("drone_has_charged", drone_id="d2")], "checks[1]", "drone_has_charged"),
    ({"logic": "not", "checks": [_leaf("drone_altitude", drone_id="d1", expected_altitude=9),
                                 _leaf("drone_hovering", drone_id="d1")]}, "checks", "not"),
    ({"logic": "not", "checks": [_leaf("drone_altitude", drone_id="d1", expected_altitude=9)]},
     "checks[0]", "drone_altitude"),
])
def test_a_leaf_it_cannot_plan_is_named_in_the_record(checks: Any, path: str,
                                                      endpoint: str) -> None:
    record = _fly(_fixed_world(), checks)
    assert record["finish"] == "agent_error"
    assert f"cannot plan {path} ({endpoint})" in record["error"]


def test_hand_plans_come_first_unless_turned_off(monkeypatch: pytest.MonkeyPatch) -> None:
    data = _fixed_world()
    data["tasks"] = [{"id": "t01", "template": "x", "category": "basic_operations",
                      "difficulty": "easy", "text": "Take off.",
                      "budget": {"tool_calls": 40, "sim_time_s": 300.0},
                      "checks": [_leaf("drone_hovering", drone_id="d1")],
                      "oracle": [[{"op": "takeoff", "drone": "d2", "altitude_m": 10}]]}]
    session = session_from_dict(data)
    hand = asyncio.run(run_one_task(session, session.tasks[0], oracle_for_session(session)))
    assert not hand["passed"]  # the (wrong) hand plan flew d2
    monkeypatch.setenv("MAVSWARM_ORACLE", "derived")
    derived = oracle_for_session(session)
    assert isinstance(derived, OracleAgent) and derived.derived_only
    _passed(asyncio.run(run_one_task(session, session.tasks[0], derived)))
    monkeypatch.setenv("MAVSWARM_ORACLE", "guess")
    with pytest.raises(ValueError, match="MAVSWARM_ORACLE='guess'"):
        oracle_for_session(session)


def test_unplannable_names_path_endpoint_and_reason() -> None:
    error = Unplannable("checks[2]", "drone_status", "why")
    assert str(error) == "cannot plan checks[2] (drone_status): why"
