"""The workflow agent's transcript on a scripted model: its plan and verdict turns in full
with their tokens and simulated times, and its tool-calling round's tool results. (Apart from
test_transcript.py: these run on pytest's event loop, which a module's browser holds.)"""

from __future__ import annotations

import json
from typing import Any

import pytest

from benchmark.authoring.session_file import session_from_dict
from benchmark.running.episode import run_session
from swarm_agents.llm import ScriptedChatModel, WorkflowAgent
from swarm_agents.llm import tool_call as call
from swarm_agents.llm.scripted import Reply
from tests.bench_fixtures import small_session

SUMMARY = "climbed and held; " + "the long account of it goes on " * 20  # > 200 characters


@pytest.mark.mavsdk
async def test_the_workflow_transcript_holds_its_plan_and_verdict_turns() -> None:
    data = small_session(["takeoff_hold"])
    op = data["tasks"][0]["oracle"][0][0]
    plan = json.dumps({"steps": [{"tool": "take_off", "arguments": {
        "drone_id": op["drone"], "altitude_m": op["altitude_m"]}}], "done_when": SUMMARY})
    script: list[Reply] = [{"role": "assistant", "content": plan},
              {"role": "assistant", "content": '{"complete": true, "reason": "holding"}'}]
    records: list[dict[str, Any]] = []
    agent = WorkflowAgent(ScriptedChatModel(script))
    await run_session(session_from_dict(data, source="s.json"), agent, emit=records.append)
    (record,) = records
    transcript = record["replay"]["transcript"]
    assert [e["role"] for e in transcript] == ["system", "user", "assistant",
                                               "system", "user", "assistant"]
    assert transcript[2]["content"] == plan  # the plan in full
    assert transcript[2]["tokens"] == transcript[5]["tokens"] == {"prompt": 100,
                                                                   "completion": 20}
    # The verifier is asked after the take-off flew: later in simulated time.
    assert transcript[3]["t_s"] > transcript[2]["t_s"]
    assert "take_off" in transcript[4]["content"]


@pytest.mark.mavsdk
async def test_the_workflow_react_round_keeps_its_last_tool_results() -> None:
    data = small_session(["takeoff_hold"])
    op = data["tasks"][0]["oracle"][0][0]
    script: list[Reply] = [{"role": "assistant", "content": "no plan"},
              {"role": "assistant", "content": "still no plan"},
              [call("take_off", {"drone_id": op["drone"], "altitude_m": op["altitude_m"]},
                    "r1")],
              [call("finish", {"summary": SUMMARY}, "r2")]]
    records: list[dict[str, Any]] = []
    agent = WorkflowAgent(ScriptedChatModel(script))
    await run_session(session_from_dict(data, source="s.json"), agent, emit=records.append)
    (record,) = records
    transcript = record["replay"]["transcript"]
    assert record["finish"] == "finished"
    assert [e["role"] for e in transcript][-4:] == ["assistant", "tool", "assistant", "tool"]
    assert [e.get("tool_call_id") for e in transcript if e["role"] == "tool"] == ["r1", "r2"]
    finish = transcript[-2]["tool_calls"][0]
    assert json.loads(finish["arguments"]) == {"summary": SUMMARY}
    assert sum(1 for e in transcript if "tokens" in e) == 4  # one per model turn
