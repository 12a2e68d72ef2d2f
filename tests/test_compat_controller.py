"""The reference's controller and benchmark harness against `mavswarm serve`, by the calls its
documentation gives (benchmark_generation.md section 6.2, checks.md section 3.2): an admin
restores a session under its id, adds a target and a task, resets the drones before the task
(land_all, charge_all), reads the task with its check tree, lets the agent fly, evaluates the
tree leaf by leaf over HTTP (lists as repeated query parameters) and marks the task done."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.compat_fixtures import KEYS, PlatClient, plat_server, plat_world

pytestmark = pytest.mark.mavsdk

D1, D2 = "d1d1d1d1", "d2d2d2d2"


def _leaf_query(parameters: dict[str, Any]) -> list[tuple[str, str | int | float | bool | None]]:
    """A leaf's parameters as the harness sends them: a list as the key repeated."""
    query: list[tuple[str, str | int | float | bool | None]] = []
    for key, value in parameters.items():
        for item in value if isinstance(value, list) else [value]:
            query.append((key, str(item)))
    return query


async def test_the_harness_sequence_runs_a_task_to_done(tmp_path: Path) -> None:
    free = plat_world()
    free["tasks"] = []
    async with plat_server(tmp_path, free) as s:
        admin = PlatClient(s.client, KEYS["admin"])
        world = plat_world()
        world["tasks"] = [{
            "id": "a11c0de1", "name": "pair_up", "difficulty": "easy",
            "content": "Take both drones off and keep them within 45 m of each other.",
            "execution_check_apis": {"logic": "and", "checks": [
                {"endpoint": "/check/drone_has_taken_off",
                 "parameters": {"drone_id": D1, "min_altitude": 4.0}},
                {"endpoint": "/check/drone_has_taken_off",
                 "parameters": {"drone_id": D2, "min_altitude": 4.0}},
                {"endpoint": "/check/drone_group_distance",
                 "parameters": {"drone_ids": [D1, D2], "max_distance": 45.0,
                                "mode": "all_pairs"}},
                {"endpoint": "/check/drone_has_landed", "parameters": {"drone_id": D1},
                 "expect": False}]}}]
        restored = await admin.post("/sessions/5e551011", world)
        assert restored["id"] == "5e551011" and s.hub.current() == "5e551011"
        await admin.post("/sessions/5e551011/set-current")
        landed = await admin.post("/drones/land_all")
        assert landed["drones_already_grounded"] == 2
        charged = await admin.post("/drones/charge_all")
        assert charged["drones_already_full"] == 2

        task = await admin.get("/sessions/5e551011/tasks/a11c0de1")
        tree = task["execution_check_apis"]
        agent = PlatClient(s.client)  # the keyless agent follows the current session
        assert (await agent.get("/sessions/current/tasks/next"))["id"] == "a11c0de1"
        for drone in (D1, D2):
            took = await agent.command(drone, "take_off", altitude=6)
            assert took["status"] == "success", took

        outcomes = []
        for leaf in tree["checks"]:
            r = await s.client.get(leaf["endpoint"], params=_leaf_query(leaf["parameters"]),
                                   headers={"X-API-Key": KEYS["admin"]})
            assert r.status_code == 200, (leaf, r.text)
            outcomes.append(r.json()["result"] is leaf.get("expect", True))
        assert outcomes == [True, True, True, True]
        server_side = await admin.get("/check/task/a11c0de1")
        assert server_side["result"] is True
        done = await admin.post("/sessions/5e551011/tasks/a11c0de1/mark-done")
        assert done["is_done"] is True and done["is_passed"] is True
