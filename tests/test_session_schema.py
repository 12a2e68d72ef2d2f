"""The published JSON Schemas of scenario and session files are generated from the pydantic
models that loading uses, and agree with what loading accepts and rejects."""

from __future__ import annotations

import copy
import json
import typing
from pathlib import Path
from typing import Any

import jsonschema
import pytest

from benchmark.authoring import session_model
from benchmark.authoring.session_file import session_from_dict
from benchmark.authoring.suite import SESSIONS_DIR
from emulator import scenario_model
from emulator.scenario import ScenarioError, scenario_from_dict
from emulator.world import OBSTACLE_KINDS, TARGET_KINDS
from tests.bench_fixtures import reference_session

FAMILIES = ("area_search", "area_assignment_and_patrol", "target_assignment",
            "target_tracking", "resilience")
SAMPLES = [SESSIONS_DIR / f"{family}-{level}-1.json" for family in FAMILIES
           for level in ("easy", "hard")]


def _validator(schema: dict[str, Any]) -> jsonschema.Draft202012Validator:
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


SCENARIO = _validator(scenario_model.json_schema())
SESSION = _validator(session_model.json_schema())


@pytest.mark.parametrize("module", [scenario_model, session_model], ids=["scenario", "session"])
def test_the_committed_schema_is_the_generated_one(module: Any) -> None:
    assert module.SCHEMA_PATH.read_text(encoding="utf-8") == module.schema_text(), (
        f"run python -m {module.__name__}")


def test_the_unions_tags_are_the_worlds_kinds() -> None:
    def tags(union: Any) -> tuple[str, ...]:
        members = typing.get_args(typing.get_args(union)[0])
        return tuple(typing.get_args(m.model_fields["type"].annotation)[0] for m in members)
    assert set(tags(scenario_model.TargetEntity)) == set(TARGET_KINDS)
    assert set(tags(scenario_model.ObstacleEntity)) == set(OBSTACLE_KINDS)


@pytest.mark.parametrize("path", SAMPLES, ids=lambda p: p.stem)
def test_shipped_sessions_meet_the_session_schema(path: Path) -> None:
    SESSION.validate(json.loads(path.read_text(encoding="utf-8")))


def test_a_multiuav_plat_export_meets_the_scenario_schema() -> None:
    data = reference_session()
    data["targets"][0].update(velocity=None, moving_path=None, charge_amount=None)  # as exported
    data["obstacles"][0].update(width=None, length=None)
    SCENARIO.validate(data)
    assert len(scenario_from_dict(data).vehicles) == 4


# Shape errors: the schema and the loader both refuse them, and the loader's message names the
# entity and the field.
SHAPE_ERRORS: list[tuple[str, Any, str]] = [
    ("drones", [], "session: drones must list at least one entry"),
    ("drones.0.max_speed", "fast", "drones[0] (id a1b1c1d1): max_speed must be a number"),
    ("drones.0.max_speed", True, "max_speed must be a number, got true"),
    ("drones.0.battery_capacity", 0, "battery_capacity must be > 0, got 0"),
    ("drones.0.name", " ", "name must be a non-empty string"),
    ("drones.0.gimbal", "yes", "gimbal must be true or false"),
    ("drones.0.position", [1, 2], "position must be an object with numbers x and y"),
    ("drones.0.position", {"x": 1}, "position must be an object with numbers x and y"),
    ("targets.0.type", "blob", "targets[0] (id 1a2b3c4d): type must be one of fixed, moving"),
    ("targets.0.radius", -1, "radius must be >= 0, got -1"),
    ("targets.2.charge_amount", 0, "targets[2] (id 9c0d1e2f): charge_amount must be > 0"),
    ("obstacles.0.radius", "3", "obstacles[0] (id 0f1e2d3c): radius must be a number"),
    ("obstacles.1.vertices", {"x": 0}, "vertices must be a list of {x, y} points"),
    ("obstacles.1.vertices.1", {"y": 3}, "vertices[1] must be an object with numbers x and y"),
    ("environment.wind_direction", "up", "environment: wind_direction must be one of north"),
    ("environment.wind_speed", -1, "environment: wind_speed must be >= 0"),
    ("safety_margin_m", "2", "session: safety_margin_m must be a number"),
]


def _set(data: Any, path: str, value: Any) -> None:
    keys: list[Any] = [int(k) if k.isdigit() else k for k in path.split(".")]
    for key in keys[:-1]:
        data = data[key]
    data[keys[-1]] = value


@pytest.mark.parametrize(("path", "value", "message"), SHAPE_ERRORS,
                         ids=[f"{p}={v!r}" for p, v, _ in SHAPE_ERRORS])
def test_the_schema_and_the_loader_refuse_the_same_shapes(path: str, value: Any,
                                                          message: str) -> None:
    data = copy.deepcopy(reference_session())
    _set(data, path, value)
    assert not SCENARIO.is_valid(data)
    with pytest.raises(ScenarioError) as caught:
        scenario_from_dict(data, source="ref.json")
    assert str(caught.value).startswith("ref.json: ") and message in str(caught.value)


def test_null_reads_as_absent_in_the_loader_and_the_schema() -> None:
    data = reference_session()
    data["drones"][0].update(heading=None, perceived_radius=None, home_position=None)
    data["targets"][0]["radius"] = None
    data["environment"] = None
    assert SCENARIO.is_valid(data)
    scenario = scenario_from_dict(data)
    assert scenario.vehicles[0].perceived_radius_m == scenario_model.DEFAULT_PERCEIVED_RADIUS_M
    assert scenario.world.target("1a2b3c4d").radius_m == scenario_model.DEFAULT_TARGET_RADIUS_M
    data["drones"][0]["name"] = None  # a required field given null is missing
    assert not SCENARIO.is_valid(data)
    with pytest.raises(ScenarioError, match=r"drones\[0\] \(id a1b1c1d1\): name is required"):
        scenario_from_dict(data)


@pytest.fixture(scope="module")
def session_data() -> dict[str, Any]:
    return json.loads((SESSIONS_DIR / "area_search-easy-1.json").read_text(encoding="utf-8"))


@pytest.mark.parametrize(("change", "message"), [
    ({"budget": {"tool_calls": 0, "sim_time_s": 10}}, "budget.tool_calls must be >= 1, got 0"),
    ({"budget": {"tool_calls": "3", "sim_time_s": 10}},
     "budget.tool_calls must be an integer, got \"3\""),
    ({"text": "  "}, "text must be a non-empty string"),
    ({"aliases": ["ok", 7]}, "aliases[1] must be a string, got 7"),
    ({"difficulty": "brutal"}, "difficulty must be one of 'easy', 'medium' or 'hard'"),
    ({"oracle": [[{"drone": "d1"}]]}, "oracle[0][0].op is required"),
    ({"oracle": [{"op": "photo"}]}, "oracle[0] must be a list"),
])
def test_a_bad_task_names_the_field_path_and_the_schema_refuses_it(
        session_data: dict[str, Any], change: dict[str, Any], message: str) -> None:
    data = copy.deepcopy(session_data)
    data["tasks"][0].update(change)
    assert not SESSION.is_valid(data)
    session = session_from_dict(data, source="s.json")
    error = session.tasks[0].error
    assert error is not None and error.startswith(f"tasks[0] (t01): {message}"), error
    assert all(task.error is None for task in session.tasks[1:])


def test_session_fields_are_named_in_errors(session_data: dict[str, Any]) -> None:
    data = copy.deepcopy(session_data)
    data["index"] = True
    with pytest.raises(ValueError, match=r"s\.json: session: index must be an integer, got true"):
        session_from_dict(data, source="s.json")
    data = copy.deepcopy(session_data)
    del data["family"]
    assert not SESSION.is_valid(data)
    with pytest.raises(ValueError, match=r"s\.json: session: family is required"):
        session_from_dict(data, source="s.json")


def test_each_endpoints_parameters_have_a_schema_that_shipped_checks_meet() -> None:
    from benchmark.scoring.validators.registry import ENDPOINTS
    from benchmark.scoring.validators.tree import _LEAF_KEYS
    validators = {name: _validator(ep.params_schema()) for name, ep in ENDPOINTS.items()}
    for name, schema in ((n, ep.params_schema()) for n, ep in ENDPOINTS.items()):
        assert set(schema["properties"]) == {p.name for p in ENDPOINTS[name].params}, name

    def leaves(node: Any) -> list[dict[str, Any]]:
        if isinstance(node, list):
            return [leaf for child in node for leaf in leaves(child)]
        if "endpoint" in node:
            return [node]
        return leaves(node.get("checks", []))
    seen: set[str] = set()
    for path in SAMPLES:
        for task in json.loads(path.read_text(encoding="utf-8"))["tasks"]:
            for leaf in leaves(task["checks"]):
                assert set(leaf) <= _LEAF_KEYS | {"name", "description"}
                validators[leaf["endpoint"]].validate(leaf.get("parameters", {}))
                seen.add(leaf["endpoint"])
    assert len(seen) >= 20
    assert not validators["drone_hovering"].is_valid({"drone_id": "d1", "tolerance": -1})


def test_an_origin_error_names_the_file_once() -> None:
    data = reference_session()
    data["origin"] = {"latitude_deg": 47.0, "longitude_deg": 8.0, "altitude_amsl_m": "high"}
    with pytest.raises(ScenarioError) as caught:
        scenario_from_dict(data, source="ref.json")
    assert str(caught.value) == 'ref.json: origin: altitude_amsl_m must be a number, got "high"'
    data["origin"] = {"latitude_deg": 95.0, "longitude_deg": 8.0}
    with pytest.raises(ScenarioError) as caught:
        scenario_from_dict(data, source="ref.json")
    assert str(caught.value).startswith("ref.json: origin: origin latitude 95")
    assert str(caught.value).count("ref.json") == 1


@pytest.mark.parametrize(("checks", "valid"), [
    ({"logic": "and", "checks": [{"endpoint": "drone_hovering",
                                  "parameters": {"drone_id": "d1", "tolerance": 0.5}}]}, True),
    ([{"endpoint": "drone_hovering", "parameters": {"drone_id": "d1"}, "expect": False}], True),
    ({"logic": "xor", "checks": []}, False),
    ({"endpoint": "drone_teleported", "parameters": {}}, False),
    ({"endpoint": "drone_hovering", "parameters": {"drone_id": "d1", "tolerance": -1}}, False),
    ({"endpoint": "drone_hovering", "parameters": {}}, False),
    ({"endpoint": "drone_group_distance", "parameters": {"drone_ids": ["d1"]}}, False),
])
def test_the_published_check_tree_types_each_endpoints_parameters(
        session_data: dict[str, Any], checks: Any, valid: bool) -> None:
    data = copy.deepcopy(session_data)
    data["tasks"][0]["checks"] = checks
    assert SESSION.is_valid(data) == valid
    assert (session_from_dict(data, source="s.json").tasks[0].error is None) == valid


def test_an_exported_scenario_meets_the_scenario_schema_and_reads_back() -> None:
    from emulator.scenario import default_scenario
    from emulator.scenario_export import scenario_to_dict
    exported = scenario_to_dict(default_scenario(12))
    errors = [e.message for e in SCENARIO.iter_errors(exported)]
    assert errors == []
    again = scenario_from_dict(exported)
    assert [v.id for v in again.vehicles] == [f"d{k}" for k in range(1, 13)]
    assert {o.kind for o in again.world.obstacles} == set(OBSTACLE_KINDS)
