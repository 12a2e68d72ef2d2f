"""An operator moves a live session on to its next task; agents cannot, and they see the new
task with a fresh budget."""

from __future__ import annotations

import pytest

from tests.bench_fixtures import small_session
from tests.rest_fixtures import as_role, served

pytestmark = pytest.mark.mavsdk


async def test_operator_moves_the_session_to_its_next_task() -> None:
    data = small_session(["takeoff_hold", "checkpoint"])
    data["tasks"].append({**data["tasks"][1], "id": "t03", "budget": "lots"})  # unusable
    async with served(data=data) as s:
        sid, drone = s.live.id, data["drones"][0]["id"]
        path = f"/sessions/{sid}/task/next"
        took = await s.client.post(f"/sessions/{sid}/tools/take_off", headers=as_role("agent"),
                                   json={"drone_id": drone, "altitude_m": 6.0})
        assert took.json()["status"] == "ok" and s.live.tools.tool_calls == 1
        refused = await s.client.post(path, headers=as_role("agent"))
        assert refused.status_code == 403 and s.live.task.id == "t01", refused.text
        moved = await s.client.post(path, headers=as_role("operator"))
        assert moved.status_code == 200, moved.text
        assert moved.json()["task"] == "t02" and moved.json()["skipped"] == []
        task = (await s.client.get(f"/sessions/{sid}/task", headers=as_role("agent"))).json()
        assert task == {"id": "t02", "text": data["tasks"][1]["text"]}
        assert s.live.tools.tool_calls == 0  # a fresh budget
        state = (await s.client.get(f"/drones/{drone}", headers=as_role("agent"))).json()
        assert state["status"] == "idle"  # reset as before every benchmark task
        last = await s.client.post(path, headers=as_role("admin"))
        assert last.status_code == 409 and "unusable: t03" in last.json()["detail"]
        assert s.live.task.id == "t02"
