"""The ReAct agent flying a real task on a real swarm: on a scripted model in process, through
malformed model output to a pass; and from `bench run --agent react` on an OpenAI-compatible
server over a real socket (the openai SDK's client end to end)."""

from __future__ import annotations

import json

import pytest

from benchmark.authoring.session_file import session_from_dict
from benchmark.running.episode import run_session
from llm_tools import default_registry, openai_tools
from swarm_agents.llm import ReactAgent, ScriptedChatModel, tool_call
from swarm_agents.llm.scripted import Reply
from tests.bench_fixtures import small_session
from tests.cli_fixtures import MAVSWARM
from tests.scripted_llm import scripted_llm


def test_tool_definitions_are_strict() -> None:
    tools = openai_tools(default_registry())
    names = [t["function"]["name"] for t in tools]
    assert len(names) == len(set(names)) == 20 and "finish" in names and "wait" in names
    for t in tools:
        params = t["function"]["parameters"]
        assert params["additionalProperties"] is False
        assert all("description" in p for p in params["properties"].values()), t
    move = next(t for t in tools if t["function"]["name"] == "move_to")["function"]
    assert move["parameters"]["required"] == ["drone_id", "x", "y", "z"]
    assert move["parameters"]["properties"]["x"]["type"] == "number"


@pytest.mark.mavsdk
async def test_react_agent_recovers_from_bad_calls_and_passes() -> None:
    data = small_session(["takeoff_hold"])
    op = data["tasks"][0]["oracle"][0][0]
    drone, altitude = op["drone"], op["altitude_m"]
    session = session_from_dict(data, source="s.json")
    script: list[Reply] = [
        {"role": "assistant", "content": "Let me think without acting."},
        [tool_call("take_off", "{drone_id: oops", "c1")],  # malformed JSON
        [tool_call("take_off", {"drone_id": drone, "altitude_m": "high"}, "c2"),  # wrong type
         tool_call("teleport", {"drone_id": drone}, "c3"),  # unknown tool
         tool_call("take_off", {"drone_id": drone}, "c4")],  # missing argument
        [tool_call("take_off", {"drone_id": drone, "altitude_m": altitude, "speed": 3}, "c5")],
        [tool_call("take_off", {"drone_id": drone, "altitude_m": altitude}, "c6")],
        [tool_call("finish", {"summary": "hovering"}, "c7")],
    ]
    records: list[dict] = []
    model = ScriptedChatModel(script)
    await run_session(session, ReactAgent(model), emit=records.append)
    (record,) = records
    assert record["passed"], record["checks"]
    assert record["finish"] == "finished" and model.remaining == 0
    # 6 answers; the scripted model prices nothing.
    assert record["tokens"] == {"prompt": 600, "completion": 120, "cost_usd": 0.0}
    # Every bad call was answered with an error the model could read, and changed nothing.
    tool_msgs = [m for m in model.requests[-1].messages if m["role"] == "tool"]
    by_id = {m["tool_call_id"]: json.loads(m["content"]) for m in tool_msgs}
    assert "not valid JSON" in by_id["c1"]["message"]
    assert "altitude_m must be a number" in by_id["c2"]["message"]
    assert "unknown tool 'teleport'" in by_id["c3"]["message"]
    assert "missing required argument(s) 'altitude_m'" in by_id["c4"]["message"]
    assert "unknown argument(s) 'speed'" in by_id["c5"]["message"]
    assert all(by_id[c]["status"] == "error" for c in ("c1", "c2", "c3", "c4", "c5"))
    assert by_id["c6"]["status"] == "ok"
    assert model.requests[0].tools[0]["type"] == "function"
    assert "Task: " in model.requests[0].messages[1]["content"]


@pytest.mark.mavsdk
def test_bench_run_with_the_react_agent(tmp_path) -> None:
    import subprocess
    from pathlib import Path

    from tests.bench_fixtures import write_json
    data = small_session(["takeoff_hold"])
    op = data["tasks"][0]["oracle"][0][0]
    session = write_json(tmp_path / "s.json", data)
    script = [[tool_call("take_off", {"drone_id": op["drone"], "altitude_m": op["altitude_m"]})],
              [tool_call("finish", {})]]
    root = Path(__file__).resolve().parents[1]
    with scripted_llm(script) as llm:
        run = subprocess.run(
            [*MAVSWARM, "bench", "run", "--agent", "react",
             "--model", "scripted", "--base-url", llm.base_url, "--sessions", str(session),
             "--out", str(tmp_path / "out"), "--price-in", "2.0", "--price-out", "8.0"],
            cwd=root, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
    record = json.loads((tmp_path / "out" / "results.jsonl").read_text())
    assert record["agent"] == "react" and record["passed"]
    assert record["tokens"] == {"prompt": 200, "completion": 40, "cost_usd": 0.00072}
    # what went over the wire: the model named, the tools offered, the results read back
    first, second = llm.requests
    assert first["model"] == "scripted" and first["tools"][0]["type"] == "function"
    assert json.loads(second["messages"][-1]["content"])["status"] == "ok"
