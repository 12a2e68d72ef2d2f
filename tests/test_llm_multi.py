"""Two sessions served at once by one REST app: each agent key reaches only its own swarm."""

from __future__ import annotations

import contextlib

import httpx
import pytest

from agent_contract import AgentTask, AgentTools, TaskBudget
from benchmark.authoring.session_file import session_from_dict
from benchmark.running.episode import swarm_gateway
from benchmark.server import Hub, LiveSession, Role, create_app
from tests.bench_fixtures import small_session

pytestmark = pytest.mark.mavsdk


async def test_two_sessions_each_agent_flies_only_its_own() -> None:
    hub = Hub()
    async with contextlib.AsyncExitStack() as stack:
        swarms = {}
        for name, family in (("a", "area_search"), ("b", "target_assignment")):
            data = {**small_session(["takeoff_hold"], family=family), "id": f"session-{name}"}
            session = session_from_dict(data, source=f"{name}.json")
            swarm, services, gateway = await stack.enter_async_context(swarm_gateway(session))
            task = session.tasks[0]
            tools = AgentTools(gateway, AgentTask(session.id, task.id, task.text,
                                                  TaskBudget(50, 600.0)))
            hub.add_session(LiveSession(session, task, swarm, services, gateway, tools,
                                        services.clock_s()))
            hub.add_key(f"key-{name}", Role.AGENT, session.id)
            swarms[name] = (swarm, data["drones"][0]["id"])
        hub.add_key("key-op", Role.OPERATOR)
        transport = httpx.ASGITransport(app=create_app(hub))
        async with httpx.AsyncClient(transport=transport, base_url="http://rest") as client:
            listed = await client.get("/sessions", headers={"X-API-Key": "key-op"})
            assert {s["id"] for s in listed.json()} == {"session-a", "session-b"}
            cross = await client.get("/sessions/session-b/drones",
                                     headers={"X-API-Key": "key-a"})
            assert cross.status_code == 403
            drone_a = swarms["a"][1]
            took = await client.post("/sessions/session-a/tools/take_off",
                                     json={"drone_id": drone_a, "altitude_m": 12},
                                     headers={"X-API-Key": "key-a"})
            assert took.status_code == 200 and took.json()["status"] == "ok", took.text
            swarm_a, swarm_b = swarms["a"][0], swarms["b"][0]
            assert any(ap.in_air for ap in swarm_a.fleet.autopilots)
            assert not any(ap.in_air for ap in swarm_b.fleet.autopilots)
            # The compatible routes pick the key's own session.
            mine = await client.get("/drones", headers={"X-API-Key": "key-b"})
            assert all(d["position"]["z"] == 0 for d in mine.json())
