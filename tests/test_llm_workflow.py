"""The workflow agent on a scripted model in process, flying real tasks on a real swarm:
plan -> execute -> verify, re-asking for malformed plans, replanning after an incomplete
verdict, and a blackboard that holds only what the tools reported."""

from __future__ import annotations

import json
from typing import Any

import pytest

from benchmark.authoring.session_file import session_from_dict
from benchmark.running.episode import run_session
from llm_tools.registry import ToolRegistry
from swarm_agents.llm import ModelConfig, ScriptedChatModel, WorkflowAgent
from swarm_agents.llm import tool_call as call
from swarm_agents.llm.blackboard import Blackboard
from swarm_agents.llm.workflow import REASK, parse_json_object, parse_plan, parse_verdict
from tests.bench_fixtures import small_session


def _text(content: str) -> dict[str, Any]:
    return {"role": "assistant", "content": content}


def _plan(*steps: tuple[str, dict[str, Any]]) -> dict[str, Any]:
    return _text(json.dumps({"steps": [{"tool": t, "arguments": a} for t, a in steps],
                             "done_when": "the drone holds its altitude"}))


def _verdict(complete: bool, reason: str) -> dict[str, Any]:
    return _text(json.dumps({"complete": complete, "reason": reason}))


def _takeoff_session() -> tuple[Any, str, float]:
    data = small_session(["takeoff_hold"])
    op = data["tasks"][0]["oracle"][0][0]
    return session_from_dict(data, source="s.json"), op["drone"], float(op["altitude_m"])


async def _run(session: Any, script: list[Any], agent_kwargs: dict[str, Any] | None = None
               ) -> tuple[dict[str, Any], ScriptedChatModel, WorkflowAgent]:
    records: list[dict[str, Any]] = []
    model = ScriptedChatModel(script)
    agent = WorkflowAgent(model, **(agent_kwargs or {}))
    await run_session(session, agent, emit=records.append)
    (record,) = records
    return record, model, agent


# ------------------------------------------------------------------ parsing (no swarm)
def test_json_object_is_found_through_fences_and_prose() -> None:
    fenced = 'Plan:\n```json\n{"steps": [], "done_when": "x"}\n```\nThat is all.'
    assert parse_json_object(fenced) == {"steps": [], "done_when": "x"}
    assert parse_json_object('{"a": {"b": 1}} trailing {"c": 2}') == {"a": {"b": 1}}
    assert parse_json_object("no json {here") is None
    assert parse_json_object("[1, 2]") is None
    assert parse_json_object(None) is None


def test_plan_and_verdict_shapes_are_checked() -> None:
    plan = parse_plan('{"steps": [{"tool": "take_off", "arguments": {"drone_id": "d1", '
                      '"altitude_m": 5}}, {"tool": "list_drones"}]}')
    assert plan is not None and [s.tool for s in plan.steps] == ["take_off", "list_drones"]
    assert plan.steps[0].drone_id == "d1" and plan.steps[1].arguments == {}
    assert parse_plan('{"steps": "take off"}') is None
    assert parse_plan('{"steps": [{"arguments": {}}]}') is None
    assert parse_plan('{"steps": [{"tool": "hover", "arguments": 3}]}') is None
    assert parse_verdict('{"complete": true, "reason": "done"}') is not None
    assert parse_verdict('```{"complete": "false"}```') == parse_verdict('{"complete": false}')
    assert parse_verdict('{"complete": "maybe"}') is None
    with pytest.raises(ValueError, match="max_rounds must be at least 1, got 0"):
        WorkflowAgent(ModelConfig(model="m"), max_rounds=0)


def test_blackboard_learns_only_from_successful_tool_results() -> None:
    board = Blackboard()
    board.ingest("nearby", {"drone_id": "d1"}, {"status": "rejected", "message": "no link",
                                                "targets": [{"id": "t9", "position": [1, 2]}]})
    assert board.targets == {} and "no link" in board.notes[0]
    board.ingest("nearby", {"drone_id": "d1"}, {
        "status": "ok", "message": "d1 senses",
        "state": {"drone": "d1", "x_m": 1.0, "y_m": 2.0, "altitude_m": 0.0},
        "targets": [{"id": "t1", "kind": "fixed", "distance_m": 3.0, "position": [4.0, 5.0, 0]}],
        "obstacles": [{"id": "o1", "kind": "circle", "distance_m": 9.0, "position": [7, 8]}],
        "drones": [{"id": "d2", "kind": "drone", "distance_m": 2.0, "position": [1, 4, 0]}]})
    assert set(board.targets) == {"t1"} and board.targets["t1"].position_m == (4.0, 5.0, 0.0)
    assert board.targets["t1"].seen_by == "d1" and set(board.obstacles) == {"o1"}
    assert board.known_ids() == {"d1", "d2", "t1", "o1"}
    board.ingest("read_messages", {"drone_id": "d2"},
                 {"status": "ok", "message": "1 new", "messages": [{"from": "d1", "text": "hi"}]})
    assert board.messages == [{"to": "d2", "from": "d1", "text": "hi"}]
    summary = json.loads(board.summary())
    assert summary["targets"][0]["id"] == "t1" and summary["drones"]["d1"]["x_m"] == 1.0


# --------------------------------------------------------------- real swarm, scripted
@pytest.mark.mavsdk
async def test_takeoff_passes_through_plan_execute_verify() -> None:
    session, drone, altitude = _takeoff_session()
    plan = _plan(("take_off", {"drone_id": drone, "altitude_m": altitude}),
                 ("finish", {"summary": "too early"}))
    fenced = {"role": "assistant",
              "content": f"Here is my plan:\n```json\n{plan['content']}\n```\nGood luck."}
    script = [fenced, _verdict(True, f"{drone} hovers at {altitude} m")]
    record, model, agent = await _run(session, script)
    assert record["passed"], record["checks"]
    assert record["finish"] == "finished"
    assert record["tokens"] == {"prompt": 200, "completion": 40, "cost_usd": 0.0}
    # Planning calls offer the model no tools.
    assert len(model.requests) == 2 and not model.requests[0].tools
    assert "Task: Take off" in model.requests[0].messages[1]["content"]
    verify_text = model.requests[1].messages[1]["content"]
    assert f'take_off({{"altitude_m":{altitude},"drone_id":"{drone}"}}) -> ok' in verify_text
    state = agent.blackboard.drones[drone]
    assert state["altitude_m"] == pytest.approx(altitude, abs=1.5)
    assert [s.tool for s in agent.blackboard.steps if s.tool not in ("list_drones", "nearby")] \
        == ["take_off", "finish"]  # the plan's own finish was dropped until verified


@pytest.mark.mavsdk
async def test_malformed_plan_is_reasked_then_succeeds() -> None:
    session, drone, altitude = _takeoff_session()
    script = [_text("I would take off the drone and then hover."),
              _plan(("take_off", {"drone_id": drone, "altitude_m": altitude})),
              _verdict(True, "hovering")]
    record, model, _ = await _run(session, script)
    assert record["passed"], record["checks"]
    assert record["tokens"] == {"prompt": 300, "completion": 60, "cost_usd": 0.0}
    reask = model.requests[1].messages
    assert reask[-2] == {"role": "assistant",
                         "content": "I would take off the drone and then hover."}
    assert reask[-1] == {"role": "user", "content": REASK}


@pytest.mark.mavsdk
async def test_unreadable_plans_fall_back_to_tool_calling() -> None:
    session, drone, altitude = _takeoff_session()
    script = [_text("not json"), _text("{still not"),
              [call("take_off", {"drone_id": drone, "altitude_m": altitude}, "c1")],
              [call("finish", {"summary": "done"}, "c2")]]
    record, model, _ = await _run(session, script)
    assert record["passed"], record["checks"]
    assert record["finish"] == "finished" and len(model.requests) == 4
    assert model.requests[2].tools and model.requests[2].tools[0]["type"] == "function"
    tool_msg = json.loads(model.requests[3].messages[-1]["content"])
    assert tool_msg["status"] == "ok"


@pytest.mark.mavsdk
async def test_incomplete_verdict_triggers_a_replan_with_the_failures() -> None:
    session, drone, altitude = _takeoff_session()
    script = [_plan(("move_to", {"drone_id": drone, "x": 0, "y": 0, "z": altitude}),
                    ("take_off", {"drone_id": drone, "altitude_m": altitude})),
              _verdict(False, "the drone is still on the ground"),
              _plan(("take_off", {"drone_id": drone, "altitude_m": altitude})),
              _verdict(True, "hovering")]
    record, model, agent = await _run(session, script)
    assert record["passed"], record["checks"]
    assert len(model.requests) == 4
    replan = model.requests[2].messages[1]["content"]
    assert "Verifier: the drone is still on the ground" in replan
    assert "Failed steps:" in replan and "move_to(" in replan
    actions = [s.tool for s in agent.blackboard.steps if s.tool not in ("list_drones", "nearby")]
    assert actions == ["move_to", "take_off", "finish"]  # round 1's take_off was skipped
    assert any("skipped take_off" in n for n in agent.blackboard.notes)


class _RecordingRegistry(ToolRegistry):
    def __init__(self) -> None:
        super().__init__()
        self.results: list[tuple[str, dict[str, Any]]] = []

    async def call(self, tools: Any, name: str, arguments: Any) -> dict[str, Any]:
        result = await super().call(tools, name, arguments)
        self.results.append((name, result))
        return result


@pytest.mark.mavsdk
async def test_blackboard_holds_only_what_the_drones_sensed() -> None:
    data = small_session(["takeoff_hold"])
    op = data["tasks"][0]["oracle"][0][0]
    home = next(d for d in data["drones"] if d["id"] == op["drone"])["position"]
    near = next(t for t in data["targets"] if t.get("position"))
    near["position"] = {"x": home["x"] + 4.0, "y": home["y"] + 3.0, "z": 0.0}
    far_ids = {t["id"] for t in data["targets"] + data["obstacles"]} - {near["id"]}
    session = session_from_dict(data, source="s.json")
    registry = _RecordingRegistry()
    script = [_plan(("take_off", {"drone_id": op["drone"], "altitude_m": op["altitude_m"]})),
              _verdict(True, "hovering")]
    _, model, agent = await _run(session, script, {"registry": registry})
    sensed: set[str] = set()
    for name, result in registry.results:
        if name == "nearby":
            sensed |= {e["id"] for key in ("targets", "obstacles", "drones")
                       for e in result.get(key, [])}
    board = agent.blackboard
    assert near["id"] in board.targets  # the test is not vacuous: something was sensed
    assert set(board.targets) | set(board.obstacles) <= sensed
    assert not (set(board.targets) | set(board.obstacles)) & far_ids - sensed
    sent = json.dumps([r.messages for r in model.requests])
    for hidden in far_ids - sensed:
        assert f'\\"{hidden}\\"' not in sent, hidden
    assert f'\\"{near["id"]}\\"' in sent  # sensed ids do reach the model
    assert "oracle" not in sent
