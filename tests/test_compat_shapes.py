"""The reference's record shapes on `mavswarm serve` (expectations in compat_expectations.py):
complete target, obstacle, environment and drone records, the session histories, command
records by id, task progress, repeated `drone_ids` query parameters, and the reference's SYSTEM
role (our operator) flying drones outside a benchmark task."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from tests.compat_expectations import (
    COMMAND_KEYS,
    COMMAND_RECORD_KEYS,
    DRONE_KEYS,
    ENVIRONMENT_KEYS,
    HISTORY_KEYS,
    OBSTACLE_KEYS,
    PROGRESS_KEYS,
    SESSION_DATA_KEYS,
    STATUS_RECORD_KEYS,
    TARGET_KEYS,
    missing,
)
from tests.compat_fixtures import KEYS, PlatClient, plat_server, plat_world

pytestmark = pytest.mark.mavsdk

D1, D2 = "d1d1d1d1", "d2d2d2d2"


async def test_records_carry_every_reference_field(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as s:
        operator = PlatClient(s.client, KEYS["operator"])
        targets = {t["id"]: t for t in await operator.get("/targets")}
        assert all(not missing(TARGET_KEYS, t) for t in targets.values()), targets
        fixed, station = targets["f1f1f1f1"], targets["a1a1a1a1"]
        assert fixed["velocity"] is None and fixed["vertices"] is None
        assert fixed["movement_mode"] == "stationary" and fixed["charge_amount"] is None
        assert station["charge_amount"] == 30.0 and fixed["radius"] == 3
        obstacles = {o["id"]: o for o in await operator.get("/obstacles")}
        assert all(not missing(OBSTACLE_KEYS, o) for o in obstacles.values()), obstacles
        assert obstacles["0b0b0b01"]["area"] == pytest.approx(math.pi * 100, abs=1e-2)
        assert obstacles["0b0b0b02"]["area"] == pytest.approx(1600.0)
        assert obstacles["0b0b0b01"]["width"] is None
        environment = await operator.get("/environments/current")
        assert not missing(ENVIRONMENT_KEYS, environment), environment
        assert environment["pressure"] == 1013.25 and environment["weather"] == "clear"
        listed = await operator.get("/drones")  # the reference's drone schema: no volume
        assert all(set(d) == DRONE_KEYS - {"battery_volume"} for d in listed)
        drones = {d["id"]: d for d in (await operator.get("/sessions/current/data"))["drones"]}
        assert all(not missing(DRONE_KEYS, d) for d in drones.values())
        assert drones[D1]["battery_volume"] == pytest.approx(
            drones[D1]["battery_level"] / 100 * 80.0, abs=0.01)
        agent = PlatClient(s.client)  # perceived records are complete too
        (seen,) = (await agent.get(f"/drones/{D2}/nearby"))["targets"]
        assert seen["id"] == "a1a1a1a1" and not missing(TARGET_KEYS, seen)


async def test_group_distance_takes_repeated_drone_ids(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as s:
        query: list[tuple[str, str | int | float | bool | None]] = [
            ("drone_ids", D1), ("drone_ids", D2), ("max_distance", "45")]
        headers = {"X-API-Key": KEYS["admin"]}
        r = await s.client.get("/check/drone_group_distance", params=query, headers=headers)
        assert r.status_code == 200, r.text
        assert r.json()["result"] is True  # 30 m apart on the ground
        r = await s.client.get("/check/drone_group_distance", headers=headers,
                               params=[("drone_ids", D1), ("drone_ids", D2),
                                       ("max_distance", "20")])
        assert r.status_code == 200 and r.json()["result"] is False
        r = await s.client.get("/check/drone_group_distance", headers=headers,
                               params=[("drone_ids", D1), ("max_distance", "20")])
        assert r.status_code == 422 and "at least 2 drones" in r.text


async def test_histories_and_command_records_follow_the_flight(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as s:
        agent, operator = PlatClient(s.client), PlatClient(s.client, KEYS["operator"])
        took = await agent.command(D1, "take_off", altitude=12)
        moved = await agent.command(D1, "move_to", x=100, y=150, z=12)
        assert {took["status"], moved["status"]} == {"success"}
        assert not missing(COMMAND_KEYS, moved)
        mine = await agent.get(f"/drones/{D1}/commands")
        assert [c["command"] for c in mine] == ["take_off", "move_to"]
        assert all(not missing(COMMAND_RECORD_KEYS, c) for c in mine)
        assert mine[1]["command_id"] == moved["command_id"]
        assert mine[1]["parameters"] == {"x": 100.0, "y": 150.0, "z": 12.0}
        one = await agent.get(f"/commands/{moved['command_id']}")
        assert one == mine[1]
        assert await agent.get(f"/drones/{D2}/commands") == []
        assert (await s.client.get("/commands/ffffffff")).status_code == 404

        data = await operator.get("/sessions/current/data")
        assert not missing(SESSION_DATA_KEYS, data) and not missing(HISTORY_KEYS,
                                                                    data["history"])
        history = data["history"]
        assert [c["command_id"] for c in history["command_history"]] == [
            took["command_id"], moved["command_id"]]
        path = history["path_history"][D1]
        assert path[0]["y"] == pytest.approx(100, abs=0.5)
        assert path[-1]["y"] == pytest.approx(150, abs=1.0)
        statuses = history["status_history"][D1]
        assert all(not missing(STATUS_RECORD_KEYS, e) for e in statuses)
        assert statuses[-1]["status"] == "hovering"
        fixed = next(t for t in data["targets"] if t["id"] == "f1f1f1f1")
        assert fixed["is_reached"] is True and fixed["reached_by"] == [D1]
        progress = await operator.get("/sessions/current/task-progress")
        assert not missing(PROGRESS_KEYS, progress)
        assert progress["details"]["visited_targets"] == ["f1f1f1f1"]
        assert progress["details"]["unvisited_targets"] == ["c1c1c1c1"]
        (sid,) = s.hub.sessions
        for route in ("command-history", "status-history", "path-history", "target-reaches",
                      "moving-target-tracking", "area-coverage"):
            assert (await s.client.get(f"/sessions/{sid}/{route}")).status_code == 403
            await operator.get(f"/sessions/{sid}/{route}")
        assert len(await operator.get(f"/sessions/{sid}/command-history")) == 2


async def test_operator_flies_only_outside_a_task(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as s:
        headers = {"X-API-Key": KEYS["operator"]}
        r = await s.client.post(f"/drones/{D1}/command/take_off", params={"altitude": 5},
                                headers=headers)
        assert r.status_code == 409 and "running benchmark task 7a5k0001" in r.text
        r = await s.client.post(f"/drones/{D1}/command", headers=headers,
                                json={"command": "take_off", "parameters": {"altitude": 5}})
        assert r.status_code == 409
    free = plat_world()
    free["tasks"], free["task_type"] = [], "others"
    async with plat_server(tmp_path, free) as s:
        operator = PlatClient(s.client, KEYS["operator"])
        took = await operator.command(D1, "take_off", altitude=5)
        assert took["status"] == "success", took
        progress = await PlatClient(s.client).get("/sessions/current/task-progress")
        assert progress["progress_percentage"] == 0 and progress["is_completed"] is False
        staff = await operator.get("/sessions/current/task-progress")
        assert staff["progress_percentage"] == 0 and staff["is_completed"] is False


async def test_waypoint_check_drone(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as s:
        agent = PlatClient(s.client)
        at = await agent.post("/targets/waypoints/a1a1a1a1/check-drone", drone_id=D2)
        assert at["is_at_waypoint"] is True and at["can_charge"] is True
        assert at["distance"] == pytest.approx(0, abs=0.5) and at["radius"] == 10
        away = await agent.post("/targets/waypoints/a1a1a1a1/check-drone", {"drone_id": D1})
        assert away["is_at_waypoint"] is False and away["distance"] == pytest.approx(30, 0.05)
        for path, params, status in (
                ("/targets/waypoints/f1f1f1f1/check-drone", {"drone_id": D1}, 404),
                ("/targets/waypoints/a1a1a1a1/check-drone", {}, 422),
                ("/targets/waypoints/a1a1a1a1/check-drone", {"drone_id": "nope"}, 404)):
            r = await s.client.post(path, params=params)
            assert r.status_code == status, (path, r.text)
