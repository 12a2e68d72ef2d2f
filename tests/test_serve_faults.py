"""`mavswarm serve` plays a task's hidden faults as `bench run` does
(benchmark.authoring.task_faults):
scheduled in simulated time from the task's start, recorded in the ground truth, undone when an
operator moves the session on; a scripted client flying a resilience task over serve's REST
routes (uvicorn on a free port, real HTTP) gets the verdict the benchmark's own episode gives
for the same plan, and no agent-facing response tells of the fault before it strikes."""

from __future__ import annotations

import asyncio
import contextlib
import json
from collections.abc import AsyncIterator, Callable
from pathlib import Path
from typing import Any

import httpx
import pytest

from agent_contract import AgentTask, AgentTools
from benchmark.authoring.session_file import session_from_dict
from benchmark.running.episode import run_session
from benchmark.server import Role, create_app
from benchmark.server.hub import LiveSession
from benchmark.server.serve import live_hub, serve_asgi
from mavlink_gateway import Outcome, Status
from tests.bench_fixtures import small_session, write_json
from tests.test_resilience_family import TELLING, _telling

pytestmark = [pytest.mark.mavsdk]

AGENT, OPERATOR, ADMIN = ({"X-API-Key": k} for k in ("k-agent", "k-operator", "k-admin"))
Step = tuple[str, dict[str, Any]]  # a tool's name and its arguments
ABOVE_BUILDINGS_M = 60.0  # the delivery world's tallest building stands 54 m


@contextlib.asynccontextmanager
async def _serving(tmp_path: Path, data: dict[str, Any], clock: str = "lockstep"
                   ) -> AsyncIterator[tuple[httpx.AsyncClient, LiveSession]]:
    """`mavswarm serve` of one session file (live_hub and create_app, as serve_rest assembles
    them, with `clock`) under uvicorn on a free port."""
    path = write_json(tmp_path / f"{data['id']}.json", data)
    async with live_hub([path], clock=clock) as hub:
        (live,) = hub.sessions.values()
        hub.add_key("k-agent", Role.AGENT, live.id)
        hub.add_key("k-operator", Role.OPERATOR)
        hub.add_key("k-admin", Role.ADMIN)
        ready: asyncio.Future[str] = asyncio.get_running_loop().create_future()
        server = asyncio.create_task(serve_asgi(create_app(hub), host="127.0.0.1", port=0,
                                                on_ready=ready.set_result))
        try:
            async with httpx.AsyncClient(base_url=await asyncio.wait_for(ready, 30.0),
                                         timeout=120.0) as client:
                yield client, live
        finally:
            server.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await server


def _delivery() -> tuple[dict[str, Any], dict[str, Any], list[list[Step]]]:
    """A resilience session with one two-parcel delivery whose first drone loses a motor, the
    task, and the plan of a client that keeps to the split: each drone carries its own parcel,
    the failing drone first: up to the task's altitude, then in straight lines above the
    world's buildings."""
    data = small_session(["delivery_despite_motor_failure"], family="resilience", seed=7)
    (task,) = data["tasks"]
    alt = next(op["z"] for phase in task["oracle"] for op in phase if op["op"] == "goto")
    cruise = ABOVE_BUILDINGS_M
    plans = []
    for k, parcel in enumerate(task["checks"]["checks"]):
        steps: list[Step] = []
        for landing in parcel["checks"][k]["checks"]:  # parcel k planned for the k-th drone
            p = landing["parameters"]
            drone = p["drone_id"]
            steps += [("take_off", {"drone_id": drone, "altitude_m": alt}),
                      ("move_to", {"drone_id": drone, "x": p["x"], "y": p["y"], "z": cruise}),
                      ("land", {"drone_id": drone})]
        plans.append(steps)
    failing = task["faults"]["failures"][0]["drone"]
    assert task["faults"]["failures"][0]["unit"] == "motor"
    assert plans[0][0][1]["drone_id"] == failing
    return data, task, plans


class _ScriptedAgent:
    """Flies `plans` with the agent tools, one drone's steps after another's; a drone whose
    step does not come back ok is left where it is."""

    name = "scripted"

    def __init__(self, plans: list[list[Step]]) -> None:
        self.plans = plans

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        for steps in self.plans:
            for name, args in steps:
                method: Callable[..., Any] = getattr(tools, name)
                outcome: Outcome = await method(**args)
                if outcome.status is not Status.OK:
                    break
        tools.finish("plan flown")


async def test_a_motor_failure_strikes_over_serve_at_its_time_and_the_verdict_is_bench_runs(
        tmp_path: Path) -> None:
    data, task, plans = _delivery()
    failure = task["faults"]["failures"][0]
    async with _serving(tmp_path, data) as (client, live):
        sid, base = live.id, f"/sessions/{live.id}"
        t0_s = live.task_start_s
        heard: list[tuple[float, str]] = []  # (simulated time answered, the response)

        async def agent_get(route: str) -> None:
            answer = await client.get(route, headers=AGENT)
            assert answer.status_code == 200, (route, answer.text)
            heard.append((live.services.clock_s(), answer.text))

        for route in (base, f"{base}/task", f"{base}/drones", f"{base}/tools", "/drones",
                      "/sessions/current", "/sessions/current/tasks",
                      "/sessions/current/tasks/next", "/sessions/current/task-progress"):
            await agent_get(route)
        for steps in plans:
            for name, args in steps:
                answer = await client.post(f"{base}/tools/{name}", headers=AGENT, json=args)
                heard.append((live.services.clock_s(), answer.text))
                await agent_get(f"{base}/drones/{args['drone_id']}")
                if answer.json()["status"] != "ok":
                    break
        # the truth records the failure at its scheduled simulated time, once
        struck = live.swarm.recorder.events(failure["drone"], kinds=["failure"])
        assert [(e.data["unit"], e.data["source"]) for e in struck] == [("motor", "schedule")]
        assert abs(struck[0].t_s - (t0_s + failure["after_s"])) <= live.swarm.fleet.dt_s + 1e-9
        at_s = struck[0].t_s
        # before it struck, nothing an agent heard told of it; afterwards outcomes do
        before = [text for t_s, text in heard if t_s < at_s - 1e-9]
        assert len(before) >= 10 and not _telling("\n".join(before), TELLING), before
        after = "\n".join(text for t_s, text in heard if t_s >= at_s - 1e-9)
        assert "Motor failure" in after
        # the hidden schedule: the admin's task view only
        for key in (AGENT, OPERATOR):
            shown = (await client.get(f"{base}/task", headers=key)).json()
            assert "faults" not in shown and "after_s" not in json.dumps(shown)
        admin = (await client.get(f"{base}/task", headers=ADMIN)).json()
        assert admin["faults"] == task["faults"]
        # the verdict over serve, on the task's window so far
        await live.swarm.wait_idle()
        served = (await client.get(f"/check/sessions/{sid}/task", headers=ADMIN)).json()
    # the same plan on bench run's path (run_session, lockstep clock)
    records: list[dict[str, Any]] = []
    await run_session(session_from_dict(data, source="bench.json"), _ScriptedAgent(plans),
                      emit=records.append)
    (record,) = records
    assert record["finish"] == "finished", record
    # the same truth event at the same simulated time from the task's start
    bench_t0_s = record["window_s"][0]
    bench_struck = [(round(t_s - bench_t0_s, 2), drone, data["unit"], data["source"])
                    for t_s, drone, kind, data in record["replay"]["events"] if kind == "failure"]
    assert bench_struck == [(round(at_s - t0_s, 2), failure["drone"], "motor", "schedule")]
    assert not served["passed"] and not record["passed"]  # the failing drone's parcel is lost
    assert [leaf["passed"] for leaf in served["leaves"]] == \
        [leaf["passed"] for leaf in record["checks"]]
    assert any(leaf["passed"] for leaf in served["leaves"])  # the healthy drone delivered


async def test_moving_on_drops_pending_failures_and_restores_the_sessions_link(
        tmp_path: Path) -> None:
    data = small_session(["delivery_despite_motor_failure", "delivery_over_lossy_link",
                          "delivery_over_lossy_link"], family="resilience", seed=7)
    del data["tasks"][2]["faults"]  # the last task flies on the session's own link
    data["link_faults"] = {"seed": 3, "downlink": {"latency_ms": 5}}
    motor = data["tasks"][0]["faults"]["failures"][0]
    (lossy,) = data["tasks"][1]["faults"]["link"]["vehicles"]
    async with _serving(tmp_path, data) as (client, live):
        base, faults = f"/sessions/{live.id}", live.swarm.faults
        recorder = live.swarm.recorder
        assert faults.next_event_s() == pytest.approx(live.task_start_s + motor["after_s"])
        moved = await client.post(f"{base}/task/next", headers=OPERATOR)
        assert moved.status_code == 200 and moved.json()["task"] == "t02", moved.text
        assert faults.next_event_s() == float("inf")  # the motor failure will not strike
        assert lossy in live.services.drone_ids
        k = live.services.drone_ids.index(lossy)
        assert faults.gate.profile(k, 0).loss == pytest.approx(0.2)  # uplink of the task
        recorded = recorder.events(lossy, kinds=["link_faults"])  # the session's, the task's
        assert [e.data["uplink"]["loss"] for e in recorded] == [0.0, 0.2]
        # operators may not read the links while the task's faults are in force; admins may
        link = f"{base}/vehicles/{lossy}/link"
        assert (await client.get(link, headers=OPERATOR)).status_code == 403
        assert (await client.get(link, headers=AGENT)).status_code == 403
        assert (await client.get(link, headers=ADMIN)).json()["uplink"]["loss"] == 0.2
        moved = await client.post(f"{base}/task/next", headers=ADMIN)
        assert moved.status_code == 200 and moved.json()["task"] == "t03", moved.text
        assert faults.gate.faults.to_json()["vehicles"] == {}
        assert faults.gate.profile(k, 0).loss == 0.0
        assert faults.gate.profile(k, 1).latency_ms == 5.0  # the session file's link again
        shown = (await client.get(f"{base}/link-faults", headers=OPERATOR)).json()
        assert shown["link_faults"]["downlink"]["latency_ms"] == 5.0
        restored = recorder.events(lossy, kinds=["link_faults"])[-1].data
        assert restored["uplink"]["loss"] == 0.0 and restored["downlink"]["latency_ms"] == 5.0
        assert not recorder.events(kinds=["failure"])
