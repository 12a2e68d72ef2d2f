"""Plug-in agents (`swarm_agents.plugins`): specs resolved from their text, factories given
the run's options, bad plug-ins refused before a run or ended as their tasks' agent_error
records while the run goes on, a hung agent stopped by the wall-clock guard (and only a hung
one), the example LLM loop (the openai SDK) against a scripted OpenAI-compatible server, and
a team of built-in ReAct agents on scripted models, one per drone."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import pytest

from agent_contract import AgentOptions, tool_names
from benchmark.authoring.session_file import Session, session_from_dict
from benchmark.running.backends import Unit
from benchmark.running.orchestrator import RunPlan, run_benchmark, run_unit
from benchmark.running.results import read_records
from swarm_agents.plugins import (
    AgentSpecError,
    BrokenAgent,
    PluginAgent,
    check_spec,
    make_agent,
    parse_spec,
)
from swarm_agents.teams.per_drone import PerDroneTeam
from tests.bench_fixtures import small_session, write_json
from tests.plugin_fixtures import write_plugins
from tests.scripted_llm import call, scripted_llm

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE_LLM = str(ROOT / "examples" / "openai_agent.py") + ":OpenAIAgent"


@pytest.fixture(scope="module")
def plugins(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_plugins(tmp_path_factory.mktemp("plugins"))


@pytest.fixture(scope="module")
def session() -> Session:
    return session_from_dict(small_session(["takeoff_hold", "checkpoint"]), source="s.json")


def test_specs_parse_from_their_text() -> None:
    assert parse_spec("noop").kind == "builtin"
    react = parse_spec("react:per-drone")
    assert (react.kind, react.target, react.per_drone) == ("builtin", "react", True)
    module = parse_spec("pkg.agents:Agent.inner:per-drone")
    assert (module.kind, module.target, module.attr, module.per_drone) == (
        "module", "pkg.agents", "Agent.inner", True)
    file = parse_spec("some/dir/agent.py:Mine")
    assert (file.kind, file.target, file.attr) == ("file", "some/dir/agent.py", "Mine")
    assert parse_spec("agent.py:Mine").kind == "file"
    assert parse_spec("my-agent").kind == "entry_point"
    for bad, reason in [("", "required"), ("external", "hosted run"),
                        ("oracle:per-drone", "no per-drone form"), ("pkg.mod:", "Python name"),
                        ("pkg.mod:1x", "Python name"), ("a b:C", "neither a module"),
                        ("agent.py", "not an agent name")]:
        with pytest.raises(AgentSpecError, match=reason):
            parse_spec(bad)


def test_bad_plugins_are_refused_before_a_run_in_one_line(plugins: Path,
                                                          tmp_path: Path) -> None:
    broken_import = tmp_path / "broken_import.py"
    broken_import.write_text("import json\nraise RuntimeError('no GPU here')\n")
    syntax = tmp_path / "syntax.py"
    syntax.write_text("class Agent(:\n")
    cases = {
        f"{plugins}:SyncRun": "not `async def`",
        f"{plugins}:NoRun": "has no run method",
        f"{plugins}:WrongRun": "does not take (task, tools)",
        f"{plugins}:NeedsTwo": "cannot be made with no arguments nor with the run's options",
        f"{plugins}:coroutine": "is a coroutine function",
        f"{plugins}:Missing": "has no 'Missing'",
        f"{broken_import}:Agent": "RuntimeError: no GPU here (broken_import.py:2)",
        f"{syntax}:Agent": "SyntaxError",
        f"{tmp_path}/absent.py:Agent": "no file",
        "no_such_package_xyz.agents:Agent": "No module named 'no_such_package_xyz'",
        "json:__version__": "a str object is not an agent",
        "json:decoder": "names a module, not an agent",
        "gpt-9": "unknown agent 'gpt-9'",
    }
    for spec, reason in cases.items():
        with pytest.raises(AgentSpecError) as caught:
            check_spec(spec)
        message = str(caught.value)
        assert reason in message and "\n" not in message, (spec, message)
    for good in ("WithOptions", "NoArguments", "instance", "factory", "FailsFirst"):
        assert check_spec(f"{plugins}:{good}").kind == "file"
    # relative to the directory the run started in, wherever the unit runs
    assert check_spec(f"{plugins.name}:factory", str(plugins.parent)).attr == "factory"


def test_factories_get_the_run_options_and_teams_one_instance_per_drone(
        plugins: Path, session: Session) -> None:
    options = AgentOptions(agent="x", session_id=session.id, trial=2, model="m",
                           base_url="http://llm", price_in_usd_per_mtok=1.5)
    for name in ("WithOptions", "factory"):
        agent = make_agent(f"{plugins}:{name}", session, options)
        assert isinstance(agent, PluginAgent) and agent.name == f"{plugins}:{name}"
        assert agent.agent.options == options
    plain = make_agent(f"{plugins}:NoArguments", session, options)
    assert isinstance(plain, PluginAgent) and plain.agent.altitude_m == 10.0  # no options given
    shared = make_agent(f"{plugins}:instance", session, options)
    assert isinstance(shared, PluginAgent) and shared.agent.altitude_m == 7.0
    spec = f"{plugins}:WithOptions:per-drone"
    team = make_agent(spec, session, options)
    assert isinstance(team, PerDroneTeam) and team.name == spec
    member = team._make("d2")
    assert isinstance(member, PluginAgent)
    assert member.agent.options.drone_id == "d2" and member.agent.options.agent == spec
    assert make_agent("noop", session, options).name == "noop"
    broken = make_agent(f"{plugins}:broken_factory", session, options)
    assert isinstance(broken, BrokenAgent) and isinstance(broken.error, KeyError)


def _run(session_file: Path, out: Path, agent: str, **kw: Any) -> list[dict[str, Any]]:
    run_benchmark(RunPlan(sessions=(session_file,), agent=agent, out_dir=out, **kw),
                  progress=lambda line: None)
    return read_records(out / "results.jsonl")


@pytest.mark.mavsdk
@pytest.mark.slow
def test_bad_plugins_end_as_agent_errors_and_the_run_goes_on(plugins: Path,
                                                             tmp_path: Path) -> None:
    session_file = write_json(tmp_path / "s.json", small_session(["takeoff_hold", "checkpoint"]))
    raises = _run(session_file, tmp_path / "raises", f"{plugins}:FailsFirst")
    assert [(r["task"], r["finish"]) for r in raises] == [("t01", "agent_error"),
                                                          ("t02", "finished")]
    assert raises[0]["error"].startswith("RuntimeError: boom in run (plugins_under_test.py:")
    assert {r["agent"] for r in raises} == {f"{plugins}:FailsFirst"}

    started = time.monotonic()
    hangs = _run(session_file, tmp_path / "hangs", f"{plugins}:HangsFirst", agent_timeout_s=1.0)
    assert time.monotonic() - started < 30.0
    assert [(r["task"], r["finish"]) for r in hangs] == [("t01", "agent_error"),
                                                         ("t02", "finished")]
    assert "no tool call" in hangs[0]["error"] and "--agent-timeout-s" in hangs[0]["error"]
    assert hangs[0]["tool_calls"] == 0

    # Six calls 0.3 s apart: longer than the timeout in all, never idle that long.
    slow = _run(session_file, tmp_path / "slow", f"{plugins}:SlowThinker", agent_timeout_s=1.0)
    assert [(r["finish"], r["tool_calls"]) for r in slow] == [("finished", 6)] * 2
    assert all(r["wall_time_s"] > 1.0 for r in slow)

    for name, reason in [("broken_factory", "KeyError: 'no model configured' "
                                            "(plugins_under_test.py:"),
                         ("makes_no_agent", "the factory made a int object, which has no run")]:
        records = _run(session_file, tmp_path / name, f"{plugins}:{name}")
        assert [r["finish"] for r in records] == ["agent_error"] * 2, name
        assert all(r["error"].startswith(reason) or reason in r["error"]
                   for r in records), records[0]["error"]


@pytest.mark.mavsdk
def test_a_plugin_gone_when_its_unit_runs_ends_its_tasks_as_agent_errors(tmp_path: Path
                                                                         ) -> None:
    """A worker (or a Ray node) resolves the spec again; what fails there is recorded."""
    session_file = write_json(tmp_path / "s.json", small_session(["takeoff_hold"]))
    plan = RunPlan(sessions=(session_file,), agent="gone.py:Agent",
                   agent_base_dir=str(tmp_path))
    sent: list[tuple[str, Any]] = []
    run_unit(plan, Unit(str(session_file), 0), sent.append)
    records = [payload for kind, payload in sent if kind == "record"]
    assert [r["finish"] for r in records] == ["agent_error"]
    assert f"no file {tmp_path / 'gone.py'}" in records[0]["error"]
    assert records[0]["agent"] == "gone.py:Agent"


@pytest.mark.mavsdk
@pytest.mark.slow
def test_the_example_llm_loop_flies_on_a_scripted_model(tmp_path: Path) -> None:
    session_file = write_json(tmp_path / "s.json", small_session(["takeoff_hold"]))
    script = [[call("take_off", {"drone_id": "d1", "altitude_m": 10.0}, "c1"),
               call("take_off", {"drone_id": "d2", "altitude_m": "high"}, "c2")],
              {"role": "assistant", "content": "All good."},
              [call("finish", {"summary": "d1 is up"}, "c3")]]
    with scripted_llm(script) as llm:
        records = _run(session_file, tmp_path / "llm", EXAMPLE_LLM, model="scripted-1",
                       base_url=llm.base_url, price_in_usd_per_mtok=2.0,
                       price_out_usd_per_mtok=10.0)
    [record] = records
    assert (record["finish"], record["error"], record["tool_calls"]) == ("finished", None, 1)
    # three model calls of 100 prompt and 20 completion tokens each, at the given prices
    assert record["tokens"] == {"prompt": 300, "completion": 60,
                                "cost_usd": round((300 * 2.0 + 60 * 10.0) / 1e6, 6)}
    first, second, third = llm.requests
    assert first["model"] == "scripted-1"
    assert [t["function"]["name"] for t in first["tools"]] == list(tool_names())
    answers = {m["tool_call_id"]: json.loads(m["content"])
               for m in second["messages"] if m["role"] == "tool"}
    assert answers["c1"]["status"] == "ok"
    assert answers["c2"]["status"] == "error" and "altitude_m" in answers["c2"]["message"]
    assert third["messages"][-1]["role"] == "user"  # nudged back to the tools after text


@pytest.mark.mavsdk
@pytest.mark.slow
def test_a_plugin_plays_per_drone(plugins: Path, tmp_path: Path) -> None:
    session_file = write_json(tmp_path / "s.json", small_session(["takeoff_hold"]))
    spec = f"{plugins}:scripted_react:per-drone"
    [record] = _run(session_file, tmp_path / "team", spec)
    # each drone's agent was told which drone it commands, took it off and finished
    assert (record["agent"], record["finish"], record["tool_calls"]) == (spec, "finished", 3)
    assert record["tokens"]["prompt"] == 600  # six model calls, two per drone
