"""Check trees: parsing, parameter validation and coercion, JSON form, logic and evaluation."""

from __future__ import annotations

import re
from typing import Any

import pytest

from benchmark.scoring.validators import (
    ENDPOINTS,
    CheckDefinitionError,
    Group,
    Leaf,
    endpoints_used,
    evaluate,
    leaf_count,
    parse_tree,
    tree_to_json,
)
from emulator.world import Obstacle, Target
from tests.scenario_fixtures import tiny_scenario, vehicle
from tests.test_validators_fixtures import context, log, rows

SCENARIO = tiny_scenario(
    [vehicle(1), vehicle(2, 20.0)],
    targets=[Target.disc("t1", "Fixed", "fixed", (50.0, 0.0, 0.0), 2.0),
             Target.disc("m1", "Mover", "moving", (80.0, 0.0, 0.0), 1.0)],
    obstacles=[Obstacle.disc("o1", "Pole", (30.0, 30.0), 2.0)],
)
# d1 hovers at 10 m over (0, 0); d2 rests on the ground at (20, 0).
TRUTH = log({"d1": rows([(0, 0, 0, 0), (2, 0, 0, 10)], t_end_s=10.0),
             "d2": rows([(0, 20, 0, 0)], t_end_s=10.0)})
CTX = context(TRUTH, SCENARIO, 0.0, 10.0)


def leaf(endpoint: str, expect: object = True, **parameters: Any) -> dict[str, Any]:
    return {"endpoint": endpoint, "parameters": parameters, "expect": expect}


def fails_with(data: object, pattern: str, scen: object = SCENARIO) -> None:
    with pytest.raises(CheckDefinitionError, match=pattern):
        parse_tree(data, scen)  # type: ignore[arg-type]


HOVERING = leaf("drone_hovering", drone_id="d1")
ON_GROUND = leaf("drone_on_ground", drone_id="d1")  # false: d1 is airborne


def test_registry_lists_every_endpoint_with_kind_and_description() -> None:
    assert len(ENDPOINTS) == 41  # the reference's 40 and moving_target_reached_in_zone
    kinds = {e.kind for e in ENDPOINTS.values()}
    assert kinds == {"state", "history", "targets"}
    assert all(name == e.name and e.description for name, e in ENDPOINTS.items())
    assert ENDPOINTS["drone_has_visited_position"].kind == "history"
    assert ENDPOINTS["task_progress"].kind == "targets"
    assert ENDPOINTS["drone_position"].to_json()["parameters"][-1] == {
        "name": "tolerance", "type": "float", "required": False, "default": 1.0, "minimum": 0.0}


def test_parse_normalises_parameters_and_fills_defaults() -> None:
    tree = parse_tree({"logic": "and", "checks": [
        leaf("/check/drone_has_visited_position", drone_id="d1", x="12.0", y=3, z=None),
        leaf("drone_has_landed", "false", drone_id="d1", min_count=2.0),
        leaf("all_drones_have_taken_off", check_history="false"),
    ]}, SCENARIO)
    assert isinstance(tree, Group)
    first, second, third = tree.checks
    assert isinstance(first, Leaf) and first.endpoint == "drone_has_visited_position"
    assert dict(first.parameters) == {"drone_id": "d1", "x": 12.0, "y": 3.0, "z": None,
                                      "tolerance": 5.0}
    assert isinstance(first.parameters["y"], float)
    assert isinstance(second, Leaf) and second.expect is False
    assert second.parameters["min_count"] == 2 and isinstance(second.parameters["min_count"], int)
    assert isinstance(third, Leaf) and third.parameters["check_history"] is False
    with pytest.raises(TypeError):
        first.parameters["x"] = 1.0  # type: ignore[index]


def test_session_id_and_since_timestamp_are_accepted_and_dropped() -> None:
    tree = parse_tree(leaf("target_is_reached", target_id="t1", session_id="s-1",
                           since_timestamp=123.0), SCENARIO)
    assert isinstance(tree, Leaf) and dict(tree.parameters) == {"target_id": "t1"}


def test_tree_to_json_round_trips() -> None:
    data = {"logic": "or", "checks": [
        leaf("drone_group_distance", drone_ids=["d1", "d2"], max_distance="30"),
        {"logic": "not", "checks": [leaf("drone_has_taken_photo", drone_id="d1",
                                         at_position='{"x": 1, "y": 2}')]},
        {"checks": []},
    ]}
    tree = parse_tree(data, SCENARIO)
    as_json = tree_to_json(tree)
    assert as_json["checks"][1]["checks"][0]["parameters"]["at_position"] == {"x": 1.0, "y": 2.0}
    assert as_json["checks"][0]["parameters"]["drone_ids"] == ["d1", "d2"]
    assert parse_tree(as_json, SCENARIO) == tree
    assert tree_to_json(parse_tree(as_json)) == as_json
    assert leaf_count(tree) == 2
    assert endpoints_used(tree) == {"drone_group_distance", "drone_has_taken_photo"}


def test_a_bare_list_is_an_and_group() -> None:
    tree = parse_tree([HOVERING, ON_GROUND])
    assert isinstance(tree, Group) and tree.logic == "and"
    assert [c.endpoint for c in tree.checks] == ["drone_hovering", "drone_on_ground"]  # type: ignore[union-attr]


@pytest.mark.parametrize(("data", "pattern"), [
    (leaf("drone_flies"), r"^checks\.endpoint: unknown endpoint 'drone_flies'"),
    (leaf("drone_hover", drone_id="d1"), r"did you mean 'drone_hovering'"),
    (leaf("drone_hovering", drone_id="d1", height=3), r"^checks\.parameters\.height: unknown "
     r"parameter for drone_hovering"),
    (leaf("drone_hovering"), r"^checks\.parameters\.drone_id: is required"),
    (leaf("drone_hovering", drone_id="d1", tolerance="abc"),
     r"^checks\.parameters\.tolerance: must be a number, got \"abc\""),
    (leaf("drone_hovering", drone_id="d1", tolerance=True), r"must be a number, got true"),
    (leaf("drone_hovering", drone_id="d1", tolerance="nan"), r"must be a finite number"),
    (leaf("drone_hovering", drone_id="d1", tolerance=-1),
     r"^checks\.parameters\.tolerance: must be >= 0, got -1"),
    (leaf("drone_has_landed", drone_id="d1", min_count=1.5), r"must be a whole number"),
    (leaf("drone_battery_level", drone_id="d1", min_level=101), r"must be <= 100, got 101"),
    (leaf("task_progress"), r"expected_progress: is required"),
    (leaf("task_progress", expected_progress=95), r"must be <= 1, got 95"),
    (leaf("drone_hovering", drone_id="d9"), r"drone 'd9' is not in scenario"),
    (leaf("drone_hovering", drone_id=7), r"must be an id \(a non-empty string\), got 7"),
    (leaf("target_is_reached", target_id="t9"), r"target 't9' is not in scenario"),
    (leaf("obstacle_within_drone_distance", drone_id="d1", obstacle_id="o9", max_distance=1),
     r"obstacle 'o9' is not in scenario"),
    (leaf("drone_has_taken_off", drone_id="d1", min_altitude=10, max_altitude=5),
     r"^checks\.parameters\.max_altitude: must be >= min_altitude \(10\), got 5"),
    (leaf("drone_has_taken_off", drone_id="d1", tolerance=-0.5), r"tolerance: must be >= 0"),
    (leaf("two_drones_distance", drone_1_id="d1", drone_2_id="d2", min_distance=5,
          max_distance=2), r"max_distance: must be >= min_distance"),
    (leaf("two_drones_distance", drone_1_id="d1", drone_2_id="d1"), r"must differ"),
    (leaf("two_drones_distance", drone_1_id="d1"), r"drone_2_id: is required"),
    (leaf("drone_group_distance", drone_ids=["d1"]), r"must list at least 2 drones"),
    (leaf("drone_group_distance", drone_ids=["d1", "d2", "d1"]),
     r"drone_ids\[2\]: drone 'd1' is listed twice"),
    (leaf("drone_group_distance", drone_ids="d1"), r"must be a list of drone ids"),
    (leaf("drone_group_distance", drone_ids=["d1", "d2"], mode="some"),
     r"mode: must be one of all_pairs, any_pair"),
    (leaf("drone_status", drone_id="d1", expected_status="asleep"), r"must be one of idle"),
    (leaf("moving_target_tracked", target_id="t1"), r"target 't1' is of kind 'fixed'"),
    (leaf("moving_target_tracked", target_id="m1", min_duration=-1), r"must be >= 0"),
    (leaf("drone_has_sent_message_content", drone_id="d1", content="  "),
     r"content: must be a non-empty string, got \"  \""),
    (leaf("drone_has_taken_photo", drone_id="d1", at_position="{x: 1}"),
     r"at_position: must be an object"),
    (leaf("drone_has_taken_photo", drone_id="d1", at_position={"x": 1}),
     r"at_position: must be an object"),
    (leaf("drone_has_taken_photo", drone_id="d1", at_position={"x": 1, "y": 2, "w": 3}),
     r"unknown key\(s\) w"),
    (leaf("drone_hovering", "maybe", drone_id="d1"), r"^checks\.expect: must be true or false"),
    (leaf("all_drones_have_landed", check_history="perhaps"),
     r"check_history: must be true or false"),
    ({"logic": "xor", "checks": []}, r"^checks\.logic: must be one of and, or, not"),
    ({"logic": "and", "checks": {"a": 1}}, r"^checks\.checks: must be a list"),
    ({"logic": "and", "chekcs": []}, r"^checks\.chekcs: unknown key in a group"),
    ({"endpoint": "drone_hovering", "paramters": {}}, r"^checks\.paramters: unknown key"),
    ("drone_hovering", r"^checks: a check node must be an object or a list"),
    ({"endpoint": "drone_hovering", "parameters": [1]},
     r"^checks\.parameters: must be an object"),
])
def test_bad_definitions_name_the_field(data: object, pattern: str) -> None:
    fails_with(data, pattern)


def test_nested_paths_in_errors() -> None:
    data = {"checks": [HOVERING, HOVERING, {"logic": "or", "checks": [
        leaf("drone_hovering", drone_id="d1", tolerance=-2)]}]}
    fails_with(data, re.escape("checks[2][0].parameters.tolerance: must be >= 0"))
    with pytest.raises(CheckDefinitionError, match=r"^tasks\[4\]\.checks\[0\]\.endpoint"):
        parse_tree([leaf("nope")], path="tasks[4].checks")


def test_ids_are_only_checked_when_a_scenario_is_given() -> None:
    tree = parse_tree(leaf("drone_hovering", drone_id="d9"))
    (result,) = evaluate(tree, CTX).leaves
    assert result.result is None and not result.passed
    assert "drone 'd9' is not in scenario" in (result.error or "")
    tree = parse_tree(leaf("moving_target_tracked", target_id="t1"))
    (result,) = evaluate(tree, CTX).leaves
    assert "of kind 'fixed'" in (result.error or "")


@pytest.mark.parametrize(("logic", "children", "passed"), [
    ("and", [], True), ("or", [], False), ("not", [], False),
    ("and", [HOVERING, HOVERING], True), ("and", [HOVERING, ON_GROUND], False),
    ("or", [ON_GROUND, HOVERING], True), ("or", [ON_GROUND, ON_GROUND], False),
    ("not", [HOVERING, ON_GROUND], True), ("not", [HOVERING, HOVERING], False),
    ("not", [ON_GROUND, ON_GROUND], True),
])
def test_group_logic(logic: str, children: list[dict[str, Any]], passed: bool) -> None:
    evaluation = evaluate(parse_tree({"logic": logic, "checks": children}, SCENARIO), CTX)
    assert evaluation.passed is passed
    assert len(evaluation.leaves) == len(children)


def test_leaf_results_record_expectation_value_and_path() -> None:
    tree = parse_tree({"checks": [HOVERING, leaf("drone_on_ground", False, drone_id="d1"),
                                  {"logic": "or", "checks": [ON_GROUND]}]}, SCENARIO)
    evaluation = evaluate(tree, CTX)
    assert not evaluation.passed
    assert [r.path for r in evaluation.leaves] == ["checks[0]", "checks[1]", "checks[2][0]"]
    assert [r.passed for r in evaluation.leaves] == [True, True, False]
    assert evaluation.passed_leaves == 2
    record = evaluation.leaves[1].to_json()
    assert record == {"path": "checks[1]", "endpoint": "drone_on_ground",
                      "parameters": {"drone_id": "d1", "tolerance": 0.1}, "expect": False,
                      "result": False, "value": 10.0, "passed": True, "error": None}


def test_a_leaf_that_cannot_run_fails_without_raising() -> None:
    history_without_d2 = log({"d1": rows([(0, 0, 0, 0)], t_end_s=10.0)})
    ctx = context(history_without_d2, SCENARIO, 0.0, 10.0)
    tree = parse_tree({"logic": "not", "checks": [leaf("drone_on_ground", drone_id="d2")]},
                      SCENARIO)
    evaluation = evaluate(tree, ctx)
    (result,) = evaluation.leaves
    assert result.result is None and result.passed is False
    assert "no record of drone 'd2'" in (result.error or "")
    assert evaluation.passed is True  # not (all children pass)


def test_context_rejects_a_reversed_window() -> None:
    with pytest.raises(ValueError, match=re.escape("t1_s=1.0 < t0_s=2.0")):
        context(TRUTH, SCENARIO, 2.0, 1.0)
