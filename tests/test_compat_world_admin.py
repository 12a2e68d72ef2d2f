"""The reference's target and obstacle writes on `mavswarm serve`: an operator adds, changes
and removes them in a world without a running task, and the swarm's perception and collision
prevention follow at once; bad bodies (422 naming the field) and unsafe edits (409) change
nothing; agents never write, and nobody does while a benchmark task runs."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest

from tests.compat_expectations import OBSTACLE_KEYS, TARGET_KEYS, missing
from tests.compat_fixtures import KEYS, PlatClient, plat_server, plat_world

pytestmark = pytest.mark.mavsdk

D1 = "d1d1d1d1"
POST = {"name": "Mast", "type": "circle", "position": {"x": 100, "y": 140}, "radius": 5}


def _free() -> dict[str, Any]:
    world = plat_world()
    world["tasks"] = []
    return world


async def test_no_writes_by_agents_or_during_a_task(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as s:
        for path in ("/targets", "/obstacles"):
            assert (await s.client.post(path, json=POST)).status_code == 403
            r = await s.client.post(path, json=POST, headers={"X-API-Key": KEYS["operator"]})
            assert r.status_code == 409, r.text
        assert len(s.hub.sessions[next(iter(s.hub.sessions))].session.scenario.world
                   .obstacles) == 2


async def test_world_edits_reach_perception_and_collision_prevention(tmp_path: Path) -> None:
    async with plat_server(tmp_path, _free()) as s:
        (sid,) = s.hub.sessions
        agent, operator = PlatClient(s.client), PlatClient(s.client, KEYS["operator"])
        headers = {"X-API-Key": KEYS["operator"]}
        for path, body, field in (
                ("/targets", {**POST, "type": "moving"}, "type"),
                ("/targets", {**POST, "type": "polygon", "vertices": [{"x": 1, "y": 1}] * 2},
                 "vertices"),
                ("/obstacles", {**POST, "radius": -1}, "radius"),
                ("/obstacles", {**POST, "colour": "red"}, "colour")):
            r = await s.client.post(path, json=body, headers=headers)
            assert r.status_code == 422 and field in r.text, (path, r.text)
        r = await s.client.post("/obstacles", headers=headers,
                                json={**POST, "position": {"x": 100, "y": 100}})
        assert r.status_code == 422 and "d1d1d1d1" in r.text, r.text  # Drone 1's start
        r = await s.client.post("/obstacles", headers=headers,
                                json={**POST, "position": {"x": 130, "y": 130}, "radius": 35})
        assert r.status_code == 422 and "a1a1a1a1" in r.text, r.text  # over the station

        spot = await operator.post("/targets", {"name": "Spot", "type": "fixed",
                                                "position": {"x": 100, "y": 130},
                                                "radius": 2})
        assert not missing(TARGET_KEYS, spot)
        near = await agent.get(f"/drones/{D1}/nearby/targets")
        assert spot["id"] in {t["id"] for t in near}  # perception follows at once
        mast = await operator.post("/obstacles", POST)
        assert not missing(OBSTACLE_KEYS, mast)
        assert mast["area"] == pytest.approx(math.pi * 25, abs=0.01)
        assert (await agent.command(D1, "take_off", altitude=10))["status"] == "success"
        moved = await agent.command(D1, "move_to", x=100, y=180, z=10)
        assert moved["status"] == "error", moved  # stopped by the new mast
        assert (await agent.get(f"/drones/{D1}"))["position"]["y"] < 135
        r = await s.client.post("/obstacles", headers=headers, json={
            **POST, "position": {"x": 106, "y": 136}, "radius": 8})
        assert r.status_code == 409 and "d1d1d1d1" in r.text, r.text  # where Drone 1 is now

        smaller = await s.client.put(f"/obstacles/{mast['id']}", json={"radius": 3},
                                     headers=headers)
        assert smaller.status_code == 200
        assert smaller.json()["area"] == pytest.approx(math.pi * 9, abs=0.01)
        retyped = await s.client.put(f"/obstacles/{mast['id']}", json={"type": "point"},
                                     headers=headers)
        assert retyped.status_code == 422 and "type" in retyped.text
        gone = await s.client.delete(f"/obstacles/{mast['id']}", headers=headers)
        assert gone.status_code == 200
        assert (await operator.http.get(f"/obstacles/{mast['id']}", headers=headers)
                ).status_code == 404
        passed = await agent.command(D1, "move_to", x=100, y=180, z=10)
        assert passed["status"] == "success", passed  # the way is clear again

        await operator.post(f"/sessions/{sid}/tasks", {
            "name": "reach", "content": "Reach the spot.",
            "execution_check_apis": {"logic": "and", "checks": [
                {"endpoint": "/check/target_is_reached_by_drone",
                 "parameters": {"target_id": spot["id"], "drone_id": D1}}]}})
        r = await s.client.delete(f"/targets/{spot['id']}", headers=headers)
        assert r.status_code == 409 and "task" in r.text
