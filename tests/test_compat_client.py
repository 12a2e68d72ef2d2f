"""A client written from the MultiUAV-Plat API documentation, unchanged, against `mavswarm serve
--open`: it reads every agent route, resolves names to ids, flies every command over the real
MAVLink swarm and completes the session's task; the admin's /check routes then pass it.
(Spec: ../shared/spec/perception_and_roles.md, commands.md, entities.md.)"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.compat_fixtures import KEYS, PlatClient, plat_server, plat_world

pytestmark = pytest.mark.mavsdk

DRONE_FIELDS = {"id", "name", "model", "status", "position", "heading", "speed",
                "perceived_radius", "task_radius", "battery_level", "battery_capacity",
                "max_speed", "max_altitude", "home_position", "created_at", "last_updated"}
SESSION_FIELDS = {"id", "name", "description", "status", "creator", "task_type",
                  "task_description", "is_distance_3d", "canvas_width", "canvas_height",
                  "created_at", "last_updated"}
PROGRESS_FIELDS = {"task_type", "progress_percentage", "is_completed", "status_message",
                   "details", "target_reach_summary", "area_coverage_summary"}


def _by_name(entities: list[dict[str, Any]]) -> dict[str, str]:
    return {e["name"]: e["id"] for e in entities}


async def _reads_the_world(agent: PlatClient) -> dict[str, str]:
    """Every read route an agent has; returns the drones' ids by name."""
    assert (await agent.get("/health"))["status"] == "online"
    assert set(await agent.get("/version")) == {"name", "version"}
    assert set(await agent.get("/")) == {"status", "message"}
    current = await agent.get("/sessions/current")
    assert set(current) >= SESSION_FIELDS and current["status"] == "active"
    assert "statistics" not in current and "targets" not in current
    task = await agent.get("/sessions/current/tasks/next")
    assert "Fixed Target 1" in task["content"]
    (listed,) = await agent.get("/sessions/current/tasks")
    assert listed["content"] == task["content"] and "checks" not in str(listed)
    drones = await agent.get("/drones")
    for drone in drones:
        assert set(drone) == DRONE_FIELDS and set(drone["position"]) == {"x", "y", "z"}
        assert drone["status"] == "idle"
    names = _by_name(drones)
    one = await agent.get(f"/drones/{names['Drone 1']}")
    assert one["name"] == "Drone 1" and one["perceived_radius"] == 60
    weather = await agent.get("/environments/current")
    assert weather["weather"] == "clear"
    progress = await agent.get("/sessions/current/task-progress")
    assert set(progress) == PROGRESS_FIELDS
    assert progress["progress_percentage"] is None and progress["is_completed"] is None
    return names


async def _flies_drone_1(agent: PlatClient, drone: str) -> dict[str, Any]:
    """Take off, find the target by name in what the drone senses, fly there, photograph it,
    rotate, hover, climb, move on, come back along a path, land. Returns the target."""
    took = await agent.command(drone, "take_off", altitude=12)
    assert took["status"] == "success", took
    nearby = await agent.get(f"/drones/{drone}/nearby")
    assert set(nearby) == {"drones", "targets", "obstacles"}
    for kind in ("drones", "targets", "obstacles"):
        one_kind = await agent.get(f"/drones/{drone}/nearby/{kind}")
        assert [e["id"] for e in one_kind] == [e["id"] for e in nearby[kind]]
    target = next(t for t in nearby["targets"] if t["name"] == "Fixed Target 1")
    assert target == await agent.get(f"/targets/{target['id']}")
    assert {t["name"] for t in nearby["targets"]} == {"Fixed Target 1", "Waypoint 1"}
    assert [t["name"] for t in await agent.get("/targets/type/waypoint")] == ["Waypoint 1"]
    assert await agent.get("/targets/type/circle") == []  # not within its drones' sensors
    assert await agent.get("/obstacles") == []
    x, y = target["position"]["x"], target["position"]["y"]
    moved = await agent.command(drone, "move_to", x=x, y=y, z=12)
    assert moved["status"] == "success", moved
    for name, params in (("take_photo", {}), ("rotate", {"heading": 90}),
                         ("hover", {"duration": 2}), ("change_altitude", {"altitude": 15}),
                         ("move_towards", {"distance": 10, "heading": 90})):
        answer = await agent.command(drone, name, **params)
        assert answer["status"] == "success", answer
    path = {"waypoints": [{"x": x + 10, "y": y + 10}, {"x": x, "y": y, "z": 12}]}
    flown = await agent.command(drone, "move_along_path", path)
    assert flown["status"] == "success", flown
    assert flown["successful_points_count"] == 2 and flown["unsuccessful_points_count"] == 0
    first = flown["successful_points"][0]  # z: the altitude at the start
    assert first[:2] == [x + 10, y + 10] and first[2] == pytest.approx(15.0, abs=0.2)
    state = await agent.get(f"/drones/{drone}")
    assert state["status"] == "hovering"
    assert abs(state["position"]["x"] - x) < 1.0 and abs(state["position"]["y"] - y) < 1.0
    landed = await agent.command(drone, "land")
    assert landed["status"] == "success", landed
    return target


async def _flies_drone_2(agent: PlatClient, drone: str, other: str) -> None:
    """Messages, a refused calibration, charging on the station it stands on, a new home and a
    return home; one command through the generic route."""
    for name, params in (("send_message", {"target_drone_id": other, "message": "hello"}),
                         ("broadcast", {"message": "all clear"}), ("charge", {}),
                         ("set_home", {})):
        answer = await agent.command(drone, name, **params)
        assert answer["status"] == "success", answer
    calibrated = await agent.command(drone, "calibrate")
    assert calibrated["status"] == "error" and "not supported" in calibrated["message"]
    took = await agent.post(f"/drones/{drone}/command",
                            {"command": "take_off", "parameters": {"altitude": 8}})
    assert took["status"] == "success", took
    home = await agent.command(drone, "return_home")
    assert home["status"] == "success", home


async def test_a_reference_client_flies_every_command_to_a_passing_task(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as served:
        agent = PlatClient(served.client)  # no key: the agent, as reference clients do
        names = await _reads_the_world(agent)
        target = await _flies_drone_1(agent, names["Drone 1"])
        await _flies_drone_2(agent, names["Drone 2"], names["Drone 1"])
        progress = await agent.get("/sessions/current/task-progress")
        assert progress["details"]["tool_calls"] > 10 and progress["is_completed"] is None

        admin = PlatClient(served.client, KEYS["admin"])
        (session_id,) = served.hub.sessions
        verdict = await admin.get(f"/check/sessions/{session_id}/task")
        assert verdict["passed"] is True, verdict
        for endpoint, params in (
                ("target_is_reached_by_drone", {"drone_id": names["Drone 1"]}),
                ("target_in_photo_taken_by_drone", {"drone_id": names["Drone 1"]})):
            leaf = await admin.get(f"/check/{endpoint}", target_id=target["id"],
                                   session_id=session_id, **params)
            assert leaf["result"] is True, leaf
        messaged = await admin.get("/check/drone_has_sent_message_content",
                                   drone_id=names["Drone 2"], content="hello")
        assert messaged["result"] is True, messaged
        staff_progress = await admin.get("/sessions/current/task-progress")
        assert staff_progress["progress_percentage"] == 50  # 1 of 2 non-station targets
        assert staff_progress["target_reach_summary"]["unique_targets_reached"] >= 1
        refused = await served.client.get(f"/check/sessions/{session_id}/task")
        assert refused.status_code == 403  # an agent never reads checks


async def test_collision_checks_see_the_map_for_staff_and_perception_for_agents(
        tmp_path: Path) -> None:
    async with plat_server(tmp_path) as served:
        agent, operator = PlatClient(served.client), PlatClient(served.client, KEYS["operator"])
        north = {"start": {"x": 100, "y": 100, "z": 12}, "end": {"x": 100, "y": 300, "z": 12}}
        assert await agent.post("/obstacles/path_collision", north) is None  # not sensed yet
        hit = await operator.post("/obstacles/path_collision", north)
        assert hit["obstacle_name"] == "Circle Obstacle 1" and hit["type"] == "circle"
        assert hit["distance"] == pytest.approx(120.0 - 10.0 - 1.0, abs=0.05)  # margin 1 m
        inside = await operator.post("/obstacles/point_collision", {"x": 100, "y": 215})
        assert inside["result"] is True and inside["inside_obstacle_ids"] == ["0b0b0b01"]
        assert inside["inside_obstacles"][0]["distance_to_boundary"] < 0
        over = await operator.post("/obstacles/point_collision",
                                   {"x": 430, "y": 130, "z": 25, "margin": 2})
        assert over["result"] is False  # above the 20 m building, beyond the margin
        under = await operator.post("/obstacles/point_collision",
                                    {"x": 430, "y": 130, "z": 21, "margin": 2})
        assert under["inside_obstacle_ids"] == ["0b0b0b02"]
        drone = (await agent.get("/drones"))[0]["id"]
        await agent.command(drone, "take_off", altitude=12)
        moved = await agent.command(drone, "move_to", x=100, y=170, z=12)
        assert moved["status"] == "success", moved
        seen = await agent.post("/obstacles/path_collision", north)
        assert seen is not None and seen["obstacle_id"] == "0b0b0b01"
        assert [o["name"] for o in await agent.get("/obstacles/type/circle")] == \
            ["Circle Obstacle 1"]
        for bad in ({"start": {"x": 1}, "end": {"x": 2, "y": 2}},
                    {"start": {"x": 1, "y": 1}, "end": {"x": 2, "y": 2}, "safety_margin": -1},
                    {"start": {"x": 1, "y": 1}, "end": {"x": 2, "y": 2}, "speed": 3},
                    [1, 2]):
            refused = await served.client.post("/obstacles/path_collision", json=bad)
            assert refused.status_code == 422, (bad, refused.text)
        unknown = await served.client.get("/targets/type/waypoints")
        assert unknown.status_code == 422 and "waypoint" in unknown.json()["detail"]
        hint = await served.client.get("/targets/waypoints")
        assert hint.status_code == 404 and "/targets/type/" in hint.json()["detail"]


async def test_staff_read_the_session_data_agents_cannot(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as served:
        (session_id,) = served.hub.sessions
        for path in ("/sessions/current/data", f"/sessions/{session_id}/data",
                     f"/sessions/{session_id}/task-progress"):
            assert (await served.client.get(path)).status_code == 403
        operator = PlatClient(served.client, KEYS["operator"])
        admin = PlatClient(served.client, KEYS["admin"])
        data = await operator.get("/sessions/current/data")
        world = plat_world()
        assert set(data) >= SESSION_FIELDS and data["id"] == session_id
        assert {d["name"] for d in data["drones"]} == {"Drone 1", "Drone 2"}
        for kind in ("targets", "obstacles"):  # the file's fields, among the reference's
            assert [{k: r[k] for k in raw} for r, raw in zip(data[kind], world[kind],
                                                              strict=True)] == world[kind]
        stats = data["statistics"]
        assert (stats["drone_count"], stats["target_count"], stats["obstacle_count"]) == (2, 3, 2)
        assert set(stats["task_progress"]) >= PROGRESS_FIELDS
        (task,) = data["tasks"]
        assert task["content"] == world["tasks"][0]["content"]
        assert task["execution_check_apis"] is None  # operators do not read check trees
        (full,) = (await admin.get(f"/sessions/{session_id}/data"))["tasks"]
        leaves = full["execution_check_apis"]["checks"]
        assert [leaf["endpoint"] for leaf in leaves] == \
            [leaf["endpoint"] for leaf in world["tasks"][0]["execution_check_apis"]["checks"]]
        assert (await operator.get("/sessions/current"))["statistics"]["drone_count"] == 2
        everything = await operator.get("/targets")
        assert [t["id"] for t in everything] == [t["id"] for t in world["targets"]]
