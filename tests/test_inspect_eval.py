"""The inspect_ai integration: `inspect eval mavswarm/smoke --model mockllm/model` as a real
subprocess, scored as a do-nothing agent is by `bench run`; a scripted mockllm flying a task
to a pass, agreeing call for call and check for check with `mavswarm bench run` on the same
transcript; tools from the one registry; bad task parameters refused."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any, cast

import pytest

pytest.importorskip("inspect_ai", reason="the inspect extra is not installed")

from inspect_ai import eval as inspect_eval
from inspect_ai.log import EvalLog, list_eval_logs, read_eval_log
from inspect_ai.model import (
    ChatCompletionChoice,
    ChatMessageAssistant,
    ModelOutput,
    ModelUsage,
    get_model,
)
from inspect_ai.solver import generate
from inspect_ai.tool import ToolCall

from agent_contract import AgentTools
from benchmark.authoring.suite import SESSIONS_DIR, SMOKE_SESSIONS, suite_paths
from benchmark.running.orchestrator import RunPlan, run_benchmark
from benchmark.running.results import read_records
from llm_tools import default_registry
from mavswarm.cli import main as mavswarm_main
from mavswarm.inspect import area_search, full, sessions, smoke, swarm_task
from mavswarm.inspect.solver import RECORD_KEY
from swarm_agents.llm.react import SYSTEM_PROMPT, task_message
from tests.bench_fixtures import overcrowded, small_session, write_json
from tests.cli_fixtures import ROOT
from tests.inspect_fixtures import INSPECT, inspect_env
from tests.scripted_llm import call, scripted_llm

USAGE = ModelUsage(input_tokens=100, output_tokens=20, total_tokens=120)  # as scripted_llm


def _verdicts(leaves: list[dict[str, Any]]) -> list[tuple[Any, ...]]:
    return [(c["path"], c["endpoint"], c["passed"], c["result"], c["value"]) for c in leaves]


def _only_log(folder: Path) -> EvalLog:
    (info,) = list_eval_logs(str(folder))
    return read_eval_log(info)


@pytest.mark.slow
@pytest.mark.mavsdk
def test_smoke_eval_on_mockllm_scores_as_a_do_nothing_agent(tmp_path: Path) -> None:
    # The first task of each smoke session (the task holds all 18: see
    # test_family_and_suite_tasks_hold_their_tasks), and `bench run`'s noop agent on the same.
    first_tasks = [f"{session}/t01" for session in SMOKE_SESSIONS]
    run = subprocess.run([INSPECT, "eval", "mavswarm/smoke", "--model", "mockllm/model",
                          "--sample-id", ",".join(first_tasks), "--display", "none"],
                         cwd=tmp_path, env=inspect_env(tmp_path),
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-3000:]
    log = _only_log(tmp_path / "logs")
    assert log.status == "success" and log.eval.task == "mavswarm/smoke"
    assert log.samples is not None and len(log.samples) == 3

    paths, _ = suite_paths("smoke")
    run_benchmark(RunPlan(sessions=paths, agent="noop", task_limit=1,
                          out_dir=tmp_path / "noop"), progress=lambda _: None)
    noop = {f"{r['session']}/{r['task']}": r for r in read_records(tmp_path / "noop" /
                                                                    "results.jsonl")}
    assert set(noop) == {str(s.id) for s in log.samples} == set(first_tasks)
    for sample in log.samples:
        # mockllm's default answer has no tool call: nudged twice, the agent stops.
        assert [m.role for m in sample.messages] == (
            ["system", "user"] + ["assistant", "user"] * 2 + ["assistant"])
        assert sample.messages[0].text == SYSTEM_PROMPT
        record = sample.store[RECORD_KEY]
        assert (record["finish"], record["error"], record["tool_calls"]) == ("finished", None, 0)
        score = sample.scores["swarm_checks"] if sample.scores else None
        assert score is not None and score.value == "I"
        expected, meta = noop[str(sample.id)], score.metadata or {}
        assert not expected["passed"]
        assert _verdicts(meta["checks"]["leaves"]) == _verdicts(expected["checks"])
        assert meta["checks_total"] == expected["checks_total"]
        assert meta["check_ratio"] == expected["checks_passed"] / expected["checks_total"]
        assert record["sim_time_s"] == expected["sim_time_s"]
    metrics = log.results.scores[0].metrics if log.results else {}
    assert metrics["accuracy"].value == 0.0
    ratios = [r["checks_passed"] / r["checks_total"] for r in noop.values()]
    assert metrics["check_ratio"].value == pytest.approx(sum(ratios) / len(ratios))


def _tool_call(op: dict[str, Any]) -> tuple[str, dict[str, Any]]:
    """An oracle step (take-off, hover) as the agent tool call that does it."""
    name = {"takeoff": "take_off", "hover": "hover"}[op["op"]]
    return name, {"drone_id": op["drone"]} | {k: v for k, v in op.items()
                                               if k not in ("op", "drone")}


def _turn(*calls: ToolCall) -> ModelOutput:
    message = ChatMessageAssistant(content="", tool_calls=list(calls), model="mockllm")
    return ModelOutput(model="mockllm", usage=USAGE,
                       choices=[ChatCompletionChoice(message=message, stop_reason="tool_calls")])


@pytest.mark.slow
@pytest.mark.mavsdk
def test_scripted_mockllm_and_bench_run_agree_on_a_transcript(tmp_path: Path) -> None:
    """Three drones launched side by side in one turn, then hovering side by side: the same
    calls through inspect and through `bench run --agent react` give the same outcomes, the
    same simulated time and the same verdict on every check."""
    data = small_session(["fleet_launch"])
    path = write_json(tmp_path / "launch.json", data)
    turns = [[_tool_call(op) for op in step] for step in data["tasks"][0]["oracle"]]
    turns.append([("finish", {"summary": "fleet up"})])

    outputs = [_turn(*(ToolCall(id=f"c{t}{k}", function=name, arguments=args)
                       for k, (name, args) in enumerate(turn)))
               for t, turn in enumerate(turns[:-1])]
    outputs.append(ModelOutput.for_tool_call("mockllm", "finish", turns[-1][0][1],
                                             tool_call_id="end"))
    outputs[-1].usage = USAGE
    model = get_model("mockllm/model", custom_outputs=outputs)
    (log,) = inspect_eval(sessions(sessions=str(path)), model=model, display="none",
                          log_dir=str(tmp_path / "logs"))
    assert log.status == "success" and log.samples is not None
    (sample,) = log.samples
    score = sample.scores["swarm_checks"] if sample.scores else None
    assert score is not None and score.value == "C", score and score.explanation
    record = sample.store[RECORD_KEY]

    script = [[call(name, args, f"c{t}{k}") for k, (name, args) in enumerate(turn)]
              for t, turn in enumerate(turns)]
    with scripted_llm(script) as llm:
        status = mavswarm_main(["bench", "run", "--agent", "react", "--model", "scripted",
                                "--base-url", llm.base_url, "--sessions", str(path),
                                "--out", str(tmp_path / "bench")])
    assert status == 0
    (bench,) = read_records(tmp_path / "bench" / "results.jsonl")
    meta = score.metadata or {}
    assert bench["passed"] and meta["checks_passed"] == bench["checks_passed"]
    assert _verdicts(meta["checks"]["leaves"]) == _verdicts(bench["checks"])
    for key in ("finish", "tool_calls", "sim_time_s", "tokens", "checks", "end_state"):
        assert record[key] == bench[key], key
    # The model read the same results, call for call.
    bench_results = [m["content"] for m in llm.requests[-1]["messages"] if m["role"] == "tool"]
    inspect_results = [m.text for m in sample.messages if m.role == "tool"]
    assert inspect_results[:-1] == bench_results  # bench's last request came before finish
    assert all(json.loads(r)["status"] == "ok" for r in inspect_results)


@pytest.mark.mavsdk
def test_a_sample_limit_ends_the_task_which_is_still_flown_out_and_scored(
        tmp_path: Path) -> None:
    data = small_session(["takeoff_hold"])
    op = data["tasks"][0]["oracle"][0][0]
    path = write_json(tmp_path / "hold.json", data)
    take_off = ModelOutput.for_tool_call(
        "mockllm", "take_off", {"drone_id": op["drone"], "altitude_m": op["altitude_m"]})
    take_off.usage = USAGE
    model = get_model("mockllm/model", custom_outputs=[take_off])
    # system, user, the take-off call: its result would be the fourth message.
    (log,) = inspect_eval(sessions(sessions=str(path)), model=model, display="none",
                          message_limit=3, log_dir=str(tmp_path / "logs"))
    assert log.samples is not None
    (sample,) = log.samples
    record = sample.store[RECORD_KEY]
    assert (record["finish"], record["error"], record["tool_calls"]) == ("finished", None, 1)
    score = sample.scores["swarm_checks"] if sample.scores else None
    assert score is not None and score.value == "C", score and score.explanation


@pytest.mark.mavsdk
def test_arguments_inspect_could_not_read_get_an_error_result_the_model_reads(
        tmp_path: Path) -> None:
    data = small_session(["takeoff_hold"])
    path = write_json(tmp_path / "hold.json", data)
    unreadable = ToolCall(id="c1", function="take_off", arguments={},
                          parse_error="Expecting value: line 1 column 2")
    outputs = [_turn(unreadable), _turn(ToolCall(id="c2", function="finish",
                                                 arguments={"summary": "gave up"}))]
    (log,) = inspect_eval(sessions(sessions=str(path)),
                          model=get_model("mockllm/model", custom_outputs=outputs),
                          display="none", log_dir=str(tmp_path / "logs"))
    assert log.samples is not None
    (sample,) = log.samples
    record = sample.store[RECORD_KEY]
    assert (record["finish"], record["tool_calls"]) == ("finished", 0)
    assert record["tokens"]["prompt"] == 200  # two turns, counted as `bench run` counts them
    tool_messages = [m for m in sample.messages if m.role == "tool"]
    assert [(m.tool_call_id, m.function) for m in tool_messages] == [("c1", "take_off"),
                                                                     ("c2", "finish")]
    refused = json.loads(tool_messages[0].text)
    assert refused["status"] == "error" and "not valid JSON" in refused["message"]
    assert "Expecting value" in refused["message"]


@pytest.mark.mavsdk
@pytest.mark.parametrize(("calls", "finish", "value"), [
    (2, "finished", "C"),  # take off, finish
    (1, "tool_call_budget", "C"),  # take off, then a hover past the budget ends the task
])
def test_an_inspect_solver_plays_a_task_with_the_registry_tools(
        tmp_path: Path, calls: int, finish: str, value: str) -> None:
    data = small_session(["takeoff_hold"])
    data["tasks"][0]["budget"]["tool_calls"] = calls
    op = data["tasks"][0]["oracle"][0][0]
    outputs = [ModelOutput.for_tool_call("mockllm", "take_off", {
                   "drone_id": op["drone"], "altitude_m": op["altitude_m"]}),
               ModelOutput.for_tool_call("mockllm", "finish" if calls == 2 else "hover", {
                   "drone_id": op["drone"], "duration_s": 5.0} if calls == 1 else {}),
               ModelOutput.from_content("mockllm", "done")]
    for output in outputs:
        output.usage = USAGE
    task = swarm_task([write_json(tmp_path / "hold.json", data)], agent=generate())
    (log,) = inspect_eval(task, model=get_model("mockllm/model", custom_outputs=outputs),
                          display="none", log_dir=str(tmp_path / "logs"))
    assert log.status == "success" and log.samples is not None
    (sample,) = log.samples
    record = sample.store[RECORD_KEY]
    assert (record["agent"], record["finish"], record["tool_calls"]) == ("inspect", finish, 1)
    score = sample.scores["swarm_checks"] if sample.scores else None
    assert score is not None and score.value == value, score and score.explanation
    tool_results = [json.loads(m.text) for m in sample.messages if m.role == "tool"]
    assert tool_results[0]["status"] == "ok"


@pytest.mark.slow
def test_tasks_that_cannot_run_score_incorrect_with_the_reason(tmp_path: Path) -> None:
    broken = small_session(["takeoff_hold"])
    broken["tasks"][0]["checks"] = {"endpoint": "no_such_check", "parameters": {}}
    crowded = overcrowded(small_session(["fleet_launch"]))  # 251 drones: no swarm can start
    crowded["id"] = "crowded"
    paths = [str(write_json(tmp_path / "broken.json", broken)),
             str(write_json(tmp_path / "crowded.json", crowded))]
    model = get_model("mockllm/model", custom_outputs=[])  # never asked
    (log,) = inspect_eval(sessions(sessions=paths), model=model, display="none",
                          log_dir=str(tmp_path / "logs"))
    assert log.status == "success" and log.samples is not None
    explained: dict[str, str] = {}
    for sample in log.samples:
        score = sample.scores["swarm_checks"] if sample.scores else None
        assert score is not None and score.value == "I"
        assert sample.store[RECORD_KEY]["finish"] == "task_error"
        explained[Path(str(sample.metadata["session_path"])).name] = str(score.explanation)
    assert "unknown endpoint 'no_such_check'" in explained["broken.json"]
    assert "the session cannot start" in explained["crowded.json"]


def test_tools_are_the_registrys() -> None:
    task = sessions(sessions="area_search-easy-1", task_limit=1)
    sample = task.dataset[0]
    assert sample.id == "area_search-easy-1/t01"
    from benchmark.authoring.importer import load_any_session
    session, _ = load_any_session(ROOT / "benchmark/sessions/area_search-easy-1.json")
    assert sample.input == task_message(session.tasks[0].text,
                                        [v.id for v in session.scenario.vehicles])
    hidden = json.dumps(sample.metadata)
    assert "checks" not in hidden and "oracle" not in hidden
    from mavswarm.inspect.tools import tool_defs
    defs = tool_defs(default_registry(), cast(AgentTools, None))  # definitions: no call runs
    specs = default_registry().specs()
    assert [d.name for d in defs] == [s.name for s in specs]
    for d, s in zip(defs, specs, strict=True):
        assert d.description == s.description
        assert d.parameters.model_dump(exclude_none=True) == s.input_schema
        assert d.parallel is False


@pytest.mark.slow
def test_family_and_suite_tasks_hold_their_tasks() -> None:
    easy = area_search(level="easy")
    assert len(easy.dataset) == 5 * 20
    assert {(s.metadata or {})["family"] for s in easy.dataset} == {"area_search"}
    assert {(s.metadata or {})["level"] for s in easy.dataset} == {"easy"}
    assert len(smoke().dataset) == 18
    assert len(full(task_limit=1).dataset) == 125


@pytest.mark.parametrize(("make", "message"), [
    (lambda: sessions(sessions="no-such-session"), "no session id or file 'no-such-session'"),
    (lambda: sessions(sessions=""), "name at least one session"),
    (lambda: area_search(level="impossible"), "unknown level(s) 'impossible'"),
    (lambda: smoke(clock="warp"), "unknown clock 'warp'"),
    (lambda: sessions(sessions="area_search-easy-1", task_limit=0), "task_limit must be >= 1"),
    (lambda: smoke(max_turns=0), "max_turns must be >= 1"),
    (lambda: sessions(sessions=["area_search-easy-1", str(SESSIONS_DIR /
                                                          "area_search-easy-1.json")]),
     "two session files hold session 'area_search-easy-1'"),
])
def test_bad_task_parameters_are_refused(make: Any, message: str) -> None:
    with pytest.raises(ValueError) as raised:
        make()
    assert message in str(raised.value)
