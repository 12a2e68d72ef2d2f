"""The lockstep clock: results that think time and machine load cannot change.

Agents that wait a random time before each tool call (seeded differently per run), alone or
one per drone talking over the radio, leave the same ground truth and the same records; the
oracle's records are identical across runs and worker counts.
"""

from __future__ import annotations

import asyncio
import hashlib
import json
import random
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from agent_contract import AgentTask, AgentTools
from benchmark.authoring.session_file import load_session
from benchmark.running.episode import EpisodeOptions, run_task, swarm_gateway
from mavlink_gateway import Status
from swarm_agents.llm import ReactAgent, ScriptedChatModel
from swarm_agents.llm import tool_call as call
from swarm_agents.oracle import OracleAgent
from swarm_agents.teams.per_drone import PerDroneTeam
from tests.cli_fixtures import MAVSWARM, ROOT, run_in_process

pytestmark = [pytest.mark.mavsdk, pytest.mark.slow]

SESSION = ROOT / "benchmark" / "sessions" / "target_assignment-easy-1.json"
WALL_FIELDS = ("wall_time_s", "overhead_s")
MAX_THINK_S = 0.3


class Thinking:
    """An agent's tools, with a random think time before every tool that acts on the world."""

    def __init__(self, tools: AgentTools, rng: random.Random) -> None:
        self._tools = tools
        self._rng = rng

    def __getattr__(self, name: str) -> Any:
        member = getattr(self._tools, name)
        if name == "concurrently" or not asyncio.iscoroutinefunction(member):
            return member

        async def call(*args: Any, **kwargs: Any) -> Any:
            await asyncio.sleep(self._rng.uniform(0.0, MAX_THINK_S))
            return await member(*args, **kwargs)
        return call


class SlowOracle:
    """The oracle, thinking before each tool call."""

    name = "oracle"

    def __init__(self, oracle: OracleAgent, seed: int) -> None:
        self._oracle = oracle
        self._rng = random.Random(seed)

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        await self._oracle.run(task, Thinking(tools, self._rng))  # type: ignore[arg-type]


class RadioDrone:
    """One drone's scripted agent: d1 scouts and reports by radio, the others wait for its
    report and then fly; each thinks a random time before every call."""

    name = "radio"

    def __init__(self, drone_id: str, seed: int) -> None:
        self.drone_id = drone_id
        self.rng = random.Random(f"{seed}/{drone_id}")
        self.log: list[tuple[str, Any]] = []

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        t = Thinking(tools, self.rng)
        me = self.drone_id
        index = int(me[1:])
        state = tools.drone_state(me).state
        assert state is not None
        x, y = state.x_m, state.y_m
        takeoff = await t.take_off(me, 8.0 + 2.0 * index)
        self.log.append(("take_off", takeoff.status))
        if me == "d1":
            self.log.append(("move", (await t.move_to(me, x + 30.0, y, 10.0)).status))
            self.log.append(("broadcast", tools.broadcast(me, "area clear, go").status))
        else:
            heard = await t.wait(me, 300.0)
            self.log.append(("heard", heard.data))
            messages = tools.read_messages(me)
            self.log.append(("read", [m["text"] for m in (messages.data or {})["messages"]]))
            self.log.append(("move", (await t.move_to(me, x, y + 20.0 * index, 12.0)).status))
        self.log.append(("land", (await t.land(me)).status))
        tools.finish(f"{me} done")


def _truth_digest(swarm: Any, t0_s: float, t1_s: float) -> str:
    recorder = swarm.recorder
    digest = hashlib.sha256()
    for vehicle in recorder.vehicle_ids:
        digest.update(np.ascontiguousarray(recorder.trajectory(vehicle, t0_s, t1_s)).tobytes())
    for event in recorder.events(t0_s=t0_s, t1_s=t1_s):
        digest.update(json.dumps([event.t_s, event.vehicle_id, event.kind, event.data],
                                 sort_keys=True, default=str).encode())
    return digest.hexdigest()


def _stable(record: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in record.items() if k not in WALL_FIELDS}


async def _fly(make_agent: Any, task_ids: list[str]) -> list[tuple[dict[str, Any], str]]:
    session = load_session(SESSION)
    tasks = [t for t in session.tasks if t.id in task_ids]
    results = []
    async with swarm_gateway(session, lockstep=True) as (swarm, services, gateway):
        for task in tasks:
            t0_s = services.clock_s()
            record = await run_task(session, task, make_agent(session), swarm, services,
                                    gateway, EpisodeOptions())
            results.append((_stable(record), _truth_digest(swarm, t0_s, services.clock_s())))
    return results


async def test_think_time_does_not_change_oracle_results() -> None:
    def oracle(seed: int):
        def make(session):
            plans = {t.id: t.oracle for t in session.tasks if t.oracle is not None}
            return SlowOracle(OracleAgent(session.scenario, plans), seed)
        return make

    tasks = ["t05", "t06"]  # three drones launched together; two drones cross-checking
    first = await _fly(oracle(1), tasks)
    second = await _fly(oracle(2), tasks)
    assert [r["passed"] for r, _ in first] == [True, True]
    assert first == second


async def test_one_agent_per_drone_over_the_radio_is_deterministic() -> None:
    runs = []
    for seed in (11, 12):
        members: dict[str, RadioDrone] = {}

        def make(session, seed=seed, members=members):
            def member(drone_id: str) -> RadioDrone:
                members[drone_id] = RadioDrone(drone_id, seed)
                return members[drone_id]
            return PerDroneTeam("radio-team", member)

        results = await _fly(make, ["t05"])
        runs.append((results, {d: m.log for d, m in members.items()}))
    (first, logs1), (second, logs2) = runs
    assert first == second and logs1 == logs2
    assert logs1["d1"][-1] == ("land", Status.OK)
    for drone, log in logs1.items():
        if drone == "d1":
            continue
        heard = dict(log)["heard"]
        assert heard["message_arrived"] is True and heard["waited_s"] > 0.0
        assert dict(log)["read"] == ["area clear, go"]
        assert dict(log)["move"] is Status.OK


def _records(path: Path) -> dict[str, dict[str, Any]]:
    rows = [json.loads(line) for line in path.read_text().splitlines()]
    return {r["key"]: _stable(r) for r in rows}


def test_oracle_smoke_records_are_identical_across_runs_and_workers(tmp_path: Path) -> None:
    """One worker (the command's main in this process) and two worker processes (a
    `mavswarm` process of its own, spawning them) give the same records."""
    runs = []
    for name, count in (("a", 1), ("b", 2)):
        out = tmp_path / name
        args = ["bench", "run", "--agent", "oracle", "--suite", "smoke", "--workers",
                str(count), "--out", str(out)]
        if count == 1:
            done = run_in_process(*args, cwd=ROOT)
        else:
            done = subprocess.run([*MAVSWARM, *args], capture_output=True, text=True,
                                  timeout=600, cwd=ROOT)
        assert done.returncode == 0, done.stderr[-2000:]
        runs.append(_records(out / "results.jsonl"))
    first, second = runs
    assert len(first) == 18 and all(r["passed"] for r in first.values())
    assert first == second
    assert {r["clock"] for r in first.values()} == {"lockstep"}


TEAM_SCRIPT = [
    [call("take_off", {"drone_id": d, "altitude_m": a}, f"t{d}")
     for d, a in (("d1", 10), ("d2", 12), ("d3", 14))],
    [call("move_towards", {"drone_id": "d1", "heading_deg": 90, "distance_m": 40}, "m1"),
     call("move_towards", {"drone_id": "d2", "heading_deg": 0, "distance_m": 30}, "m2"),
     call("hover", {"drone_id": "d3", "duration_s": 5}, "h3")],
    [call("land", {"drone_id": d}, f"l{d}") for d in ("d1", "d2", "d3")],
    [call("finish", {"summary": "done"})],
]
PER_DRONE_SCRIPTS = {
    "d1": [[call("take_off", {"drone_id": "d1", "altitude_m": 10})],
           [call("move_towards", {"drone_id": "d1", "heading_deg": 90, "distance_m": 40})],
           [call("broadcast", {"drone_id": "d1", "text": "go"})],
           [call("land", {"drone_id": "d1"})], [call("finish", {"summary": "d1"})]],
    "d2": [[call("take_off", {"drone_id": "d2", "altitude_m": 12})],
           [call("wait", {"drone_id": "d2", "duration_s": 300})],
           [call("read_messages", {"drone_id": "d2"})],
           [call("move_towards", {"drone_id": "d2", "heading_deg": 0, "distance_m": 30})],
           [call("land", {"drone_id": "d2"})], [call("finish", {"summary": "d2"})]],
    "d3": [[call("take_off", {"drone_id": "d3", "altitude_m": 14})],
           [call("wait", {"drone_id": "d3", "duration_s": 300})],
           [call("land", {"drone_id": "d3"})], [call("finish", {"summary": "d3"})]],
}


@pytest.mark.parametrize("per_drone", [False, True], ids=["team", "per-drone"])
async def test_react_agents_with_random_model_latency_are_deterministic(per_drone: bool) -> None:
    runs = []
    for seed in (21, 22):
        rng = random.Random(seed)
        models: list[ScriptedChatModel] = []

        def react(script: list[Any], rng: random.Random = rng,
                  models: list[ScriptedChatModel] = models) -> ReactAgent:
            models.append(ScriptedChatModel(
                list(script), think_s=lambda: rng.uniform(0.0, MAX_THINK_S)))
            return ReactAgent(models[-1])

        def make(session: Any, react: Any = react) -> Any:
            if per_drone:
                return PerDroneTeam("react:per-drone",
                                    lambda d: react(PER_DRONE_SCRIPTS[d]))
            return react(TEAM_SCRIPT)

        results = await _fly(make, ["t05"])
        outcomes = {m["tool_call_id"]: json.loads(m["content"])
                    for model in models for request in model.requests
                    for m in request.messages if m["role"] == "tool"}
        assert len(models) == (3 if per_drone else 1)
        assert all(model.remaining == 0 for model in models)
        runs.append(results)
        record = results[0][0]
        assert record["finish"] == "finished" and record["tokens"]["prompt"] > 0
        assert record["tool_calls"] == (12 if per_drone else 9)  # finish is free
        assert outcomes and all(o["status"] == "ok" for o in outcomes.values()), outcomes
    assert runs[0] == runs[1]


def test_per_drone_agents_are_named_on_the_command_line() -> None:
    from benchmark.running.orchestrator import AGENTS, RunPlan, make_agent

    session = load_session(SESSION)
    plan = RunPlan(sessions=(), agent="react:per-drone", model="m", base_url="http://x/v1")
    agent = make_agent("react:per-drone", session, plan)
    assert "workflow:per-drone" in AGENTS
    assert isinstance(agent, PerDroneTeam) and agent.name == "react:per-drone"
    assert isinstance(agent._make("d2"), ReactAgent)
