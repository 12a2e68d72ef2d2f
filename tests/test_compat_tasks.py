"""The reference's task routes on `mavswarm serve`: reading tasks (masked for agents), admin-only
task checks, mark-done/pending, and operators creating, replacing, swapping and deleting a
session's tasks outside a benchmark task (409 while one runs); bodies validated (422 naming
the field)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.compat_expectations import TASK_KEYS, missing
from tests.compat_fixtures import KEYS, PlatClient, plat_server, plat_world

pytestmark = pytest.mark.mavsdk

TASK = "7a5k0001"
D1 = "d1d1d1d1"


def _task(content: str, **extra: Any) -> dict[str, Any]:
    return {"name": "climb", "content": content, "difficulty": "easy",
            "execution_check_apis": {"logic": "and", "checks": [
                {"endpoint": "/check/drone_has_taken_off",
                 "parameters": {"drone_id": D1, "min_altitude": 4.0}}]}, **extra}


async def test_reading_checking_and_marking_tasks_per_role(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as s:
        (sid,) = s.hub.sessions
        agent, operator = PlatClient(s.client), PlatClient(s.client, KEYS["operator"])
        admin = PlatClient(s.client, KEYS["admin"])
        mine = await agent.get(f"/sessions/current/tasks/{TASK}")
        assert not missing(TASK_KEYS, mine) and mine["content"].startswith("Take off Drone 1")
        assert mine["execution_check_apis"] is None and mine["related_apis"] == []
        assert (await s.client.get("/sessions/current/tasks/nope")).status_code == 404
        for path in (f"/sessions/current/tasks/{TASK}/check", f"/check/task/{TASK}",
                     f"/sessions/{sid}/tasks", f"/sessions/{sid}/tasks/{TASK}"):
            assert (await s.client.get(path)).status_code == 403, path
        for path in (f"/sessions/current/tasks/{TASK}/check", f"/check/task/{TASK}"):
            r = await s.client.get(path, headers={"X-API-Key": KEYS["operator"]})
            assert r.status_code == 403, path
        verdict = await admin.get(f"/check/task/{TASK}")
        assert verdict["result"] is False and len(verdict["details"]["leaves"]) == 4
        assert verdict["task"]["execution_check_apis"]["checks"][0]["endpoint"] == \
            "/check/drone_has_taken_off"
        assert (await s.client.post(f"/sessions/current/tasks/{TASK}/mark-done")
                ).status_code == 403
        done = await operator.post(f"/sessions/current/tasks/{TASK}/mark-done")
        assert done["is_done"] is True
        pending = await operator.post(f"/sessions/{sid}/tasks/{TASK}/mark-pending")
        assert pending["is_done"] is False
        listed = await operator.get(f"/sessions/{sid}/tasks")
        assert [t["id"] for t in listed] == [TASK] and listed[0]["is_done"] is False
        r = await s.client.post(f"/sessions/{sid}/tasks", json=_task("Climb."),
                                headers={"X-API-Key": KEYS["operator"]})
        assert r.status_code == 409 and "running benchmark task" in r.text
        assert len(s.hub.sessions[sid].session.tasks) == 1


async def test_operators_edit_the_tasks_of_a_world_without_a_running_task(
        tmp_path: Path) -> None:
    free = plat_world()
    free["tasks"] = []
    async with plat_server(tmp_path, free) as s:
        (sid,) = s.hub.sessions
        operator, admin = PlatClient(s.client, KEYS["operator"]), PlatClient(s.client,
                                                                             KEYS["admin"])
        headers = {"X-API-Key": KEYS["operator"]}
        for body, field in ((_task("x", difficulty="extreme"), "difficulty"),
                            ({"name": "no content"}, "content"),
                            (_task("x", content_aliases="one"), "content_aliases")):
            r = await s.client.post(f"/sessions/{sid}/tasks", json=body, headers=headers)
            assert r.status_code == 422 and field in r.text, r.text
        bad = _task("Climb.")
        bad["execution_check_apis"]["checks"][0]["endpoint"] = "/check/drone_can_fly"
        r = await s.client.post(f"/sessions/{sid}/tasks", json=bad, headers=headers)
        assert r.status_code == 422 and "drone_can_fly" in r.text
        assert s.hub.sessions[sid].session.tasks == ()  # refused bodies changed nothing

        first = await operator.post(f"/sessions/{sid}/tasks", _task("Climb to 5 m."))
        assert not missing(TASK_KEYS, first) and first["execution_check_apis"] is None
        second = await operator.post(f"/sessions/{sid}/tasks", _task("Climb again."))
        order = await operator.post(f"/sessions/{sid}/tasks/swap",
                                    {"task_id_1": first["id"], "task_id_2": second["id"]})
        assert [t["id"] for t in order] == [second["id"], first["id"]]
        changed = await operator.http.put(f"/sessions/{sid}/tasks/{first['id']}",
                                          json=_task("Climb to 6 m."), headers=headers)
        assert changed.status_code == 200 and changed.json()["content"] == "Climb to 6 m."
        gone = await s.client.delete(f"/sessions/{sid}/tasks/{second['id']}", headers=headers)
        assert gone.status_code == 200
        assert (await s.client.delete(f"/sessions/{sid}/tasks/{second['id']}",
                                      headers=headers)).status_code == 404
        full = await admin.get(f"/sessions/{sid}/tasks/{first['id']}")
        assert full["execution_check_apis"]["checks"][0]["parameters"]["drone_id"] == D1

        took = await operator.command(D1, "take_off", altitude=6)
        assert took["status"] == "success", took
        verdict = await admin.get(f"/check/task/{first['id']}")
        assert verdict["result"] is True and verdict["task"]["is_passed"] is True
        assert (await operator.get(f"/sessions/{sid}/tasks"))[0]["is_passed"] is True

        moved = await operator.post(f"/sessions/{sid}/task/next")  # the task now runs
        assert moved["task"] == first["id"]
        r = await s.client.delete(f"/sessions/{sid}/tasks/{first['id']}", headers=headers)
        assert r.status_code == 409
