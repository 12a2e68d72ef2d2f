"""Bad session files, bad tasks and crashing agents: clear errors, and the run goes on."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from agent_contract import AgentTask, AgentTools
from benchmark.authoring.session_file import SessionFileError, load_session, session_from_dict
from benchmark.running.episode import run_session
from benchmark.running.orchestrator import RunPlan, run_benchmark
from benchmark.running.results import read_records
from tests.bench_fixtures import reference_session, small_session, write_json


@pytest.fixture(scope="module")
def good() -> dict:
    return small_session(["takeoff_hold", "climb_and_face"])


def test_corrupt_partial_and_foreign_files_name_the_file(tmp_path: Path, good: dict) -> None:
    corrupt = tmp_path / "corrupt.json"
    corrupt.write_text("{not json")
    with pytest.raises(SessionFileError, match=r"corrupt\.json: not valid JSON"):
        load_session(corrupt)
    partial = tmp_path / "partial.json"
    partial.write_text(json.dumps(good)[:500])
    with pytest.raises(SessionFileError, match=r"partial\.json: not valid JSON"):
        load_session(partial)
    with pytest.raises(SessionFileError, match=r"MultiUAV-Plat session.*mavswarm bench import"):
        load_session(write_json(tmp_path / "reference.json", reference_session()))
    missing = dict(good)
    del missing["drones"]
    with pytest.raises(SessionFileError, match="drones"):
        session_from_dict(missing, source="m.json")
    bad_drone = json.loads(json.dumps(good))
    bad_drone["drones"][1]["max_speed"] = "fast"
    with pytest.raises(SessionFileError, match=r"drones\[1\].*max_speed"):
        session_from_dict(bad_drone, source="d.json")


@pytest.mark.parametrize(("mutate", "fragments"), [
    (lambda t: t["checks"]["checks"][0].update(endpoint="drone_teleported"),
     ["tasks[0] (t01)", "checks[0]", "drone_teleported"]),
    (lambda t: t["checks"]["checks"][0]["parameters"].update(tolerance=-2),
     ["tasks[0] (t01)", "parameters.tolerance"]),
    (lambda t: t["checks"]["checks"][0]["parameters"].update(drone_id="d99"),
     ["tasks[0] (t01)", "drone_id", "d99"]),
    (lambda t: t["checks"]["checks"][0]["parameters"].update(speed_of_light=1),
     ["tasks[0] (t01)", "speed_of_light"]),
    (lambda t: t.update(budget={"tool_calls": 0, "sim_time_s": 10}),
     ["tasks[0] (t01)", "budget", "tool_calls"]),
    (lambda t: t.pop("text"), ["tasks[0] (t01)", "text"]),
])
def test_a_bad_task_is_marked_and_the_others_load(good: dict, mutate, fragments) -> None:
    data = json.loads(json.dumps(good))
    mutate(data["tasks"][0])
    session = session_from_dict(data, source="bad.json")
    bad, fine = session.tasks
    assert bad.error is not None and fine.error is None
    for fragment in fragments:
        assert fragment in bad.error, (fragment, bad.error)


class CrashingAgent:
    """Crashes on the first task, does the second properly."""

    name = "crashy"

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        if task.task_id == "t01":
            await tools.take_off(tools.drone_ids[0], 10.0)
            raise ZeroDivisionError("the model divided by zero")
        tools.finish()


class GreedyAgent:
    """Calls tools past its budget."""

    name = "greedy"

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        while True:
            tools.list_drones()


@pytest.mark.mavsdk
async def test_crashing_agent_and_bad_task_do_not_stop_the_session(good: dict) -> None:
    data = json.loads(json.dumps(good))
    data["tasks"].append(dict(data["tasks"][1], id="t03"))
    data["tasks"][2]["checks"] = {"logic": "xor", "checks": []}
    session = session_from_dict(data, source="s.json")
    records: list[dict] = []
    await run_session(session, CrashingAgent(), emit=records.append)
    assert [r["task"] for r in records] == ["t01", "t02", "t03"]
    crashed, fine, broken = records
    assert crashed["finish"] == "agent_error" and not crashed["passed"]
    assert "ZeroDivisionError: the model divided by zero" in crashed["error"]
    assert crashed["tool_calls"] == 1 and crashed["checks_total"] == 3
    assert fine["finish"] == "finished"
    assert broken["finish"] == "task_error"
    assert "s.json" in broken["error"] and "tasks[2] (t03)" in broken["error"]
    assert "xor" in broken["error"]


@pytest.mark.mavsdk
async def test_budget_ends_a_task(good: dict) -> None:
    session = session_from_dict(good, source="s.json")
    records: list[dict] = []
    await run_session(session, GreedyAgent(), emit=records.append)
    budget = good["tasks"][0]["budget"]["tool_calls"]
    assert records[0]["finish"] == "tool_call_budget"
    assert records[0]["tool_calls"] == budget


def test_unreadable_session_is_reported_and_others_run(tmp_path: Path, good: dict) -> None:
    corrupt = tmp_path / "corrupt.json"
    corrupt.write_text('{"schema": "mavswarm.session/1", "id": ')
    ok = write_json(tmp_path / "ok.json", good)
    lines: list[str] = []
    outcome = run_benchmark(RunPlan(sessions=(corrupt, ok), agent="noop",
                                    out_dir=tmp_path / "out"), progress=lines.append)
    assert len(outcome.errors) == 1 and "corrupt.json" in outcome.errors[0]
    assert len(read_records(tmp_path / "out" / "results.jsonl")) == 2
