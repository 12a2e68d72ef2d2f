"""Oracle plan steps are types: every plan a session file or the derived planner writes reads
as them, a bad step is refused naming where and why, and the oracle runs every kind."""

from __future__ import annotations

import json
import typing
from typing import Any

import pytest

from benchmark.authoring.plan_steps import (
    STEP_TYPES,
    DroneStep,
    Goto,
    Home,
    Intercept,
    Step,
    Sweep,
    Waypoints,
    parse_plan,
    parse_step,
)
from benchmark.authoring.session_file import load_session, task_from_dict
from benchmark.authoring.suite import SESSIONS_DIR

SESSION_FILES = sorted(SESSIONS_DIR.glob("*.json"))


def _stored_plans() -> list[Any]:
    return [task["oracle"] for path in SESSION_FILES
            for task in json.loads(path.read_text(encoding="utf-8"))["tasks"]
            if task.get("oracle") is not None]


def test_every_stored_plan_reads_and_writes_back() -> None:
    kinds = set()
    for raw in _stored_plans():
        plan = parse_plan(raw)
        for raw_phase, phase in zip(raw, plan, strict=True):
            for raw_step, step in zip(raw_phase, phase, strict=True):
                kinds.add(step.op)
                assert step.model_dump(mode="json") == raw_step
                assert parse_step(step.model_dump(mode="json")) == step
    # every kind but "meet", which only the derived planner writes
    assert kinds == set(STEP_TYPES) - {"meet"}


def test_one_type_per_op() -> None:
    types = set(typing.get_args(Step))
    assert types == set(STEP_TYPES.values()) and len(types) == 22
    assert all(STEP_TYPES[t.model_fields["op"].default] is t for t in types)
    assert Sweep not in typing.get_args(DroneStep)


def test_values_are_typed() -> None:
    step = parse_step({"op": "goto", "drone": "d1", "x": 1, "y": 2.5, "z": 20})
    assert step == Goto(drone="d1", x=1.0, y=2.5, z=20.0) and isinstance(step.x, float)
    assert parse_step({"op": "home", "drone": "d1"}) == Home(drone="d1", altitude_m=20.0)
    path = parse_step({"op": "path", "drone": "d1", "points": [[0, 0, 10], [5, 5, 10]]})
    assert isinstance(path, Waypoints) and path.points == ((0.0, 0.0, 10.0), (5.0, 5.0, 10.0))
    zone = parse_step({"op": "intercept", "drone": "d1", "target": "t", "zone": [1, 2, 3],
                       "altitude_m": 15})
    assert isinstance(zone, Intercept) and zone.zone == (1.0, 2.0, 3.0)
    with pytest.raises(Exception, match="frozen"):
        step.x = 3.0


@pytest.mark.parametrize(("raw", "reason"), [
    ({"op": "fly", "drone": "d1"}, r"\('fly'\): 'op' must be one of altitude, broadcast"),
    ({"drone": "d1"}, r"\(None\): 'op' must be one of"),
    ({"op": "goto", "drone": "d1", "x": 1, "y": 2}, r"\('goto'\): z: field required"),
    ({"op": "hover", "drone": "d1", "duration_s": "5"},
     r"\('hover'\): duration_s: input should be a valid number"),
    ({"op": "hover", "drone": "d1", "duration_s": True},
     r"\('hover'\): duration_s: input should be a valid number"),
    ({"op": "land", "drone": "d1", "speed": 3},
     r"\('land'\): speed: extra inputs are not permitted"),
    ({"op": "path", "drone": "d1", "points": [[1, 2]]},
     r"\('path'\): points\.0\.2: field required"),
    ({"op": "sweep", "drones": "d1", "target": "a", "altitude_m": 9}, r"\('sweep'\): drones: "),
    ("land", r": expected an operation object with 'op'"),
])
def test_a_bad_step_is_refused_by_name(raw: Any, reason: str) -> None:
    with pytest.raises(ValueError, match=r"^tasks\[0\]\.oracle\[0\]\[1\] ?" + reason):
        parse_plan([[{"op": "land", "drone": "d1"}, raw]], "tasks[0].oracle")


def test_a_session_task_with_a_bad_plan_is_kept_with_its_error() -> None:
    session = load_session(SESSION_FILES[0])
    raw = json.loads(SESSION_FILES[0].read_text(encoding="utf-8"))["tasks"][0]
    assert raw["id"] == "t01"
    raw = {**raw, "oracle": [[{"op": "takeoff", "drone": "d1", "altitude": 20}]]}
    spec = task_from_dict(0, raw, session.scenario)
    assert spec.error == "tasks[0] (t01).oracle[0][0] ('takeoff'): altitude_m: field required"
    assert spec.oracle is None
