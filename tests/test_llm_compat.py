"""A client written against MultiUAV-Plat's agent routes flies a task on a real MAVLink swarm
through the compatibility layer, and the hidden checks (admin only) pass."""

from __future__ import annotations

import httpx
import pytest

from tests.rest_fixtures import KEYS, served

pytestmark = pytest.mark.mavsdk


class PlatClient:
    """What an agent written for MultiUAV-Plat does: read the task, its drones, command them."""

    def __init__(self, http: httpx.AsyncClient, key: str) -> None:
        self.http = http
        self.headers = {"X-API-Key": key}

    async def get(self, path: str) -> object:
        response = await self.http.get(path, headers=self.headers)
        response.raise_for_status()
        return response.json()

    async def command(self, drone: str, name: str, **params: object) -> dict:
        response = await self.http.post(f"/drones/{drone}/command/{name}", params=params,
                                        headers=self.headers)
        response.raise_for_status()
        return response.json()


async def test_a_reference_style_client_flies_a_task_to_a_pass() -> None:
    async with served() as s:
        http, hub, data = s.client, s.hub, s.data
        agent = PlatClient(http, KEYS["agent"])
        task = await agent.get("/sessions/current/tasks/next")
        assert task["content"] == data["tasks"][0]["text"] and set(task) == {"id", "content"}
        drones = await agent.get("/drones")
        assert {d["id"] for d in drones} == {d["id"] for d in data["drones"]}  # type: ignore[union-attr]
        op = data["tasks"][0]["oracle"][0][0]  # the test knows the answer; the client does not
        result = await agent.command(op["drone"], "take_off", altitude=op["altitude_m"])
        assert result["status"] == "success", result
        seen = await agent.get(f"/drones/{op['drone']}/nearby")
        assert set(seen) == {"drones", "targets", "obstacles"}  # type: ignore[arg-type]
        state = await agent.get(f"/drones/{op['drone']}")
        assert abs(state["position"]["z"] - op["altitude_m"]) < 1.0  # type: ignore[index]
        # The agent cannot run the checks; the admin can, and the task passed.
        (sid,) = hub.sessions
        denied = await http.get(f"/check/sessions/{sid}/task", headers=agent.headers)
        assert denied.status_code == 403
        verdict = await http.get(f"/check/sessions/{sid}/task",
                                 headers={"X-API-Key": KEYS["admin"]})
        assert verdict.status_code == 200 and verdict.json()["passed"] is True, verdict.json()


async def test_entities_by_id_only_within_perception_and_generic_commands() -> None:
    async with served() as s:
        http, data = s.client, s.data
        agent = PlatClient(http, KEYS["agent"])
        drone = data["drones"][0]["id"]
        seen = await agent.get(f"/drones/{drone}/nearby")
        visible = {e["id"] for e in seen["targets"]}  # type: ignore[index]
        for target in data["targets"]:
            r = await http.get(f"/targets/{target['id']}", headers=agent.headers)
            if target["id"] in visible:
                assert r.status_code == 200 and r.json()["id"] == target["id"]
            else:
                assert r.status_code == 404 and "perception" in r.json()["detail"]
        # The operator sees any target by id.
        any_target = data["targets"][0]["id"]
        r = await http.get(f"/targets/{any_target}", headers={"X-API-Key": KEYS["operator"]})
        assert r.status_code == 200
        current = await agent.get("/sessions/current")
        assert "targets" not in current and "checks" not in str(current)  # type: ignore[operator]
        r = await http.post(f"/drones/{drone}/command", headers=agent.headers,
                            json={"command": "take_off", "parameters": {"altitude": 8}})
        assert r.status_code == 200 and r.json()["status"] == "success", r.text
        r = await http.post(f"/drones/{drone}/command", headers=agent.headers,
                            json={"command": "warp", "parameters": {}})
        assert r.status_code == 404 and "take_off" in r.json()["detail"]
