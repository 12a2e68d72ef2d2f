"""The lockstep clock for agents outside the process: `serve` (REST) and `mcp` hold simulated
time while the agent thinks between requests, so an external agent's results do not depend on
its think time or on the surface it uses.

The same scripted decisions (tests/external_agent.py: plain and batch calls over three drones)
are made by a separate client process over REST (httpx) and over MCP (the official SDK client),
with random think delays and with none, and in-process on the tools as `bench run` runs an
agent; the tool outcomes, the tools' call log (simulated start and end of every call) and the
ground truth of the window are identical. `MAVSWARM_MAX_THINK_S` sets the largest think delay
(default 0.5 s; the `slow` test uses 2 s).
"""

from __future__ import annotations

import asyncio
import contextlib
import copy
import hashlib
import io
import json
import os
import sys
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from agent_contract import AgentTask
from benchmark.authoring.session_file import session_from_dict
from benchmark.running.episode import swarm_gateway
from benchmark.running.tool_log import LoggedTools
from benchmark.server.hub import Hub, LiveSession
from benchmark.server.serve import serve_mcp, serve_rest
from llm_tools.registry import served_registry
from mavlink_gateway.pacing import Thinker, run_as
from tests.cli_fixtures import ROOT
from tests.external_agent import STEPS

pytestmark = [pytest.mark.mavsdk]

SESSION = ROOT / "benchmark" / "sessions" / "target_assignment-easy-1.json"
MAX_THINK_S = float(os.environ.get("MAVSWARM_MAX_THINK_S", "0.5"))
LOSSY = {"loss": 0.2, "seed": 5}


def _session_data(link_faults: dict[str, Any] | None = None) -> dict[str, Any]:
    data = json.loads(SESSION.read_text())
    data["tasks"] = data["tasks"][:1]
    if link_faults is not None:
        data["link_faults"] = link_faults
    return data


def _truth_digest(live_swarm: Any, t0_s: float, t1_s: float) -> str:
    recorder = live_swarm.recorder
    digest = hashlib.sha256()
    for vehicle in recorder.vehicle_ids:
        digest.update(np.ascontiguousarray(recorder.trajectory(vehicle, t0_s, t1_s)).tobytes())
    for event in recorder.events(t0_s=t0_s, t1_s=t1_s):
        digest.update(json.dumps([event.t_s, event.vehicle_id, event.kind, event.data],
                                 sort_keys=True, default=str).encode())
    return digest.hexdigest()


def _fingerprint(swarm: Any, tools: LoggedTools, t0_s: float, now_s: float,
                 results: list[Any]) -> dict[str, Any]:
    """What must not depend on the surface or the think time: every result the agent got,
    the call log with simulated times, the truth digest and where the clock stands. Every
    outcome is checked against the ground truth first."""
    _agrees_with_truth(swarm, tools.call_log())
    return {"results": json.loads(json.dumps(results)), "calls": tools.call_log(),
            "truth": _truth_digest(swarm, t0_s, now_s), "window_s": [t0_s, now_s]}


_BASELINES: dict[str, dict[str, Any]] = {}


async def _in_process(data: dict[str, Any]) -> dict[str, Any]:
    """The decisions made in-process, as `bench run` runs an agent: one thread of control,
    calls side by side with `tools.concurrently`. Flown once per session data in this module:
    the tests compare the other surfaces with the same in-process run."""
    key = json.dumps(data, sort_keys=True)
    if key not in _BASELINES:
        _BASELINES[key] = await _fly_in_process(data)
    return copy.deepcopy(_BASELINES[key])


async def _fly_in_process(data: dict[str, Any]) -> dict[str, Any]:
    session = session_from_dict(data, source="lockstep-serve")
    task = session.tasks[0]
    assert task.budget is not None
    registry = served_registry()
    async with swarm_gateway(session, lockstep=True,
                             link_faults=_faults(session)) as (swarm, services, gateway):
        tools = LoggedTools(gateway, AgentTask(session.id, task.id, task.text, task.budget))
        t0_s = services.clock_s()

        async def agent() -> list[Any]:
            results: list[Any] = []
            for kind, calls in STEPS:
                if kind == "call":
                    (name, args), = calls
                    results.append(await registry.call(tools, name, args))
                else:
                    results.append(await tools.concurrently(
                        *(registry.call(tools, n, a) for n, a in calls)))
            return results

        thinker = Thinker(services)
        try:
            results = await run_as(thinker, agent())
            return _fingerprint(swarm, tools, t0_s, services.clock_s(), results)
        finally:
            thinker.close()


def _faults(session: Any) -> Any:
    from benchmark.running.episode import session_link_faults
    return session_link_faults(session)


async def _client(*args: str) -> list[Any]:
    """tests/external_agent.py as a separate process; its results."""
    process = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "tests.external_agent", *args, cwd=ROOT,
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE,
        env={**os.environ, "PYTHONPATH": str(ROOT)})
    out, err = await asyncio.wait_for(process.communicate(), 300.0)
    assert process.returncode == 0, err.decode()[-3000:]
    return list(json.loads(out.decode().splitlines()[-1]))


@contextlib.asynccontextmanager
async def _running(server: Any, ready: asyncio.Future[str]) -> AsyncIterator[str]:
    task = asyncio.create_task(server)
    done, _ = await asyncio.wait({task, ready}, timeout=60.0,
                                 return_when=asyncio.FIRST_COMPLETED)
    if task in done:
        task.result()
    assert ready in done, "the server did not become ready within 60 s"
    try:
        yield ready.result()
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task


async def _over_rest(tmp_path: Path, data: dict[str, Any], seed: int, max_think_s: float,
                     clock: str = "lockstep") -> dict[str, Any]:
    path = tmp_path / f"rest-{seed}.json"
    path.write_text(json.dumps(data))
    hubs: list[Hub] = []
    ready: asyncio.Future[str] = asyncio.get_running_loop().create_future()

    def extend(app: Any, hub: Hub, keys: Any) -> None:
        hubs.append(hub)

    server = serve_rest([path], port=0, keys=["agent=k-agent"], on_ready=ready.set_result,
                        out=io.StringIO(), extend=extend, clock=clock)
    async with _running(server, ready) as url:
        results = await _client("rest", url, "k-agent", data["id"], "--seed", str(seed),
                                "--max-think-s", str(max_think_s))
        live = hubs[0].sessions[data["id"]]
        return _live_fingerprint(live, results)


async def _over_mcp(tmp_path: Path, data: dict[str, Any], seed: int,
                    max_think_s: float) -> dict[str, Any]:
    path = tmp_path / f"mcp-{seed}.json"
    path.write_text(json.dumps(data))
    lives: list[LiveSession] = []
    ready: asyncio.Future[str] = asyncio.get_running_loop().create_future()
    server = serve_mcp(path, transport="http", port=0, on_ready=ready.set_result,
                       on_session=lives.append)
    async with _running(server, ready) as url:
        results = await _client("mcp", url, "--seed", str(seed),
                                "--max-think-s", str(max_think_s))
        return _live_fingerprint(lives[0], results)


def _live_fingerprint(live: LiveSession, results: list[Any]) -> dict[str, Any]:
    assert isinstance(live.tools, LoggedTools)
    return _fingerprint(live.swarm, live.tools, live.task_start_s, live.services.clock_s(),
                        results)


def _check_outcomes(print_: dict[str, Any]) -> None:
    """The decisions did what they say: every flight ok, the one bad call an error."""
    results = print_["results"]
    assert [r["status"] for r in results[1]] == ["ok", "ok"], results[1]
    assert results[2]["status"] == "ok", results[2]
    assert [r["status"] for r in results[3]] == ["ok", "ok", "error", "ok"], results[3]
    assert "altitude_m" in results[3][2]["message"]
    assert results[4]["status"] == "ok", results[4]
    assert [r["status"] for r in results[6]] == ["ok", "ok"], results[6]
    assert results[7] == {"status": "ok", "message": "task finished"}


async def test_external_agents_over_rest_and_mcp_match_in_process(tmp_path: Path) -> None:
    data = _session_data()
    baseline = await _in_process(data)
    _check_outcomes(baseline)
    runs = {"rest, no think": await _over_rest(tmp_path, data, 1, 0.0),
            "rest, thinking": await _over_rest(tmp_path, data, 2, MAX_THINK_S),
            "mcp, no think": await _over_mcp(tmp_path, data, 3, 0.0),
            "mcp, thinking": await _over_mcp(tmp_path, data, 4, MAX_THINK_S)}
    for name, run in runs.items():
        assert run == baseline, name


@pytest.mark.slow
async def test_think_times_up_to_two_seconds_change_nothing(tmp_path: Path) -> None:
    data = _session_data()
    baseline = await _in_process(data)
    assert await _over_rest(tmp_path, data, 5, max(MAX_THINK_S, 2.0)) == baseline
    assert await _over_mcp(tmp_path, data, 6, max(MAX_THINK_S, 2.0)) == baseline


def _agrees_with_truth(live_swarm: Any, calls: list[dict[str, Any]]) -> None:
    """Every flight's outcome is what the ground truth shows at its end: a take-off ok at its
    altitude, a landing ok on the ground, a move ok where it was sent; none refused."""
    recorder = live_swarm.recorder
    assert all(c["status"] != "rejected" for c in calls), calls
    for call in calls:
        args, at = call["args"], call["t1_s"]
        if call["status"] == "error":
            continue
        assert call["status"] == "ok", call
        if call["name"] == "take_off":
            z = recorder.position_at(args["drone_id"], at)[2]
            assert z == pytest.approx(args["altitude_m"], abs=1.0), call
        elif call["name"] == "land":
            assert recorder.position_at(args["drone_id"], at)[2] < 0.3, call
        elif call["name"] == "move_towards":
            start = np.array(recorder.position_at(args["drone_id"], call["t0_s"])[:2])
            end = np.array(recorder.position_at(args["drone_id"], at)[:2])
            assert np.linalg.norm(end - start) == pytest.approx(args["distance_m"], abs=2.0)


async def test_on_a_lossy_link_every_outcome_agrees_with_the_truth(tmp_path: Path) -> None:
    """A fifth of the datagrams lost both ways: every call's outcome agrees with the ground
    truth (checked in `_fingerprint`: take-offs at their altitude, landings on the ground,
    moves their distance), none is refused, and every call ends with the same status at the
    same simulated time over REST, over MCP and in-process. The drone states that reads return
    are the telemetry that got through by then, so they are not compared here."""
    data = _session_data(LOSSY)
    baseline = await _in_process(data)
    served = await _over_rest(tmp_path, data, 7, MAX_THINK_S)
    over_mcp = await _over_mcp(tmp_path, data, 8, MAX_THINK_S)
    for run in (baseline, served, over_mcp):
        _check_outcomes(run)
    for run in (served, over_mcp):
        assert _statuses(run["results"]) == _statuses(baseline["results"])
        assert _timeline(run["calls"]) == _timeline(baseline["calls"])
        assert run["window_s"] == baseline["window_s"]


def _timeline(calls: list[dict[str, Any]]) -> list[tuple[Any, ...]]:
    return [(c["name"], c["drone"], c["t0_s"], c["t1_s"], c["status"]) for c in calls]


def _statuses(results: list[Any]) -> list[Any]:
    return [[r["status"] for r in step] if isinstance(step, list) else step["status"]
            for step in results]
