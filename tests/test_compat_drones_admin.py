"""The reference's operator drone routes on `mavswarm serve`: land_all (blocked over an
obstacle), charge_all, battery and position (placed on the ground, flown in the air), in the
reference's response shapes; never for an agent key, 409 while a benchmark task runs, bodies
validated (422 naming the field)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.compat_expectations import DRONE_KEYS, LAND_ALL_DETAIL_KEYS, LAND_ALL_KEYS, missing
from tests.compat_fixtures import KEYS, PlatClient, plat_server, plat_world

pytestmark = pytest.mark.mavsdk

D1, D2 = "d1d1d1d1", "d2d2d2d2"
ROUTES: list[tuple[str, str, Any]] = [
    ("POST", "/drones/land_all", None), ("POST", "/drones/charge_all", None),
    ("POST", f"/drones/{D1}/battery", {"battery_level": 50}),
    ("PUT", f"/drones/{D1}/position", {"x": 90, "y": 90, "z": 0})]


def _free() -> dict[str, Any]:
    world = plat_world()
    world["tasks"] = []
    return world


async def test_agents_never_and_operators_not_during_a_task(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as s:
        operator = {"X-API-Key": KEYS["operator"]}
        for method, path, body in ROUTES:
            r = await s.client.request(method, path, json=body)
            assert r.status_code == 403, (path, r.text)
            r = await s.client.request(method, path, json=body,
                                       headers={"X-API-Key": KEYS["agent"]})
            assert r.status_code == 403, (path, r.text)
            r = await s.client.request(method, path, json=body, headers=operator)
            if path.endswith("_all"):  # every drone landed and full: a harness's no-op
                assert r.status_code == 200, (path, r.text)
                continue
            assert r.status_code == 409 and "running benchmark task" in r.text, (path, r.text)
        levels = {d["battery_level"] for d in await PlatClient(s.client).get("/drones")}
        assert levels == {100.0}  # nothing changed
        took = await PlatClient(s.client).command(D1, "take_off", altitude=5)
        assert took["status"] == "success"
        for path in ("/drones/land_all", "/drones/charge_all"):  # now they would change it
            r = await s.client.post(path, headers=operator)
            assert r.status_code == 409, (path, r.text)


async def test_operator_resets_in_the_reference_shapes(tmp_path: Path) -> None:
    async with plat_server(tmp_path, _free()) as s:
        operator = PlatClient(s.client, KEYS["operator"])
        headers = {"X-API-Key": KEYS["operator"]}
        for body, field in (({"battery_level": 120}, "battery_level"),
                            ({"level": 5}, "battery_level")):
            r = await s.client.post(f"/drones/{D1}/battery", json=body, headers=headers)
            assert r.status_code == 422 and field in r.text
        r = await s.client.put(f"/drones/{D1}/position", json={"x": 1, "y": 2, "z": -3},
                               headers=headers)
        assert r.status_code == 422 and "z" in r.text
        r = await s.client.post("/drones/nope/battery", json={"battery_level": 5},
                                headers=headers)
        assert r.status_code == 404

        drone = await operator.post(f"/drones/{D1}/battery", {"battery_level": 42.5})
        assert set(drone) == DRONE_KEYS - {"battery_volume"}
        assert drone["battery_level"] == pytest.approx(42.5, abs=1.0)
        charged = await operator.post("/drones/charge_all")
        assert charged["drones_charged"] == 1 and charged["total_drones"] == 2
        assert {d["action"] for d in charged["details"]} == {"charged", "already_full"}
        assert (await operator.get(f"/drones/{D1}"))["battery_level"] == pytest.approx(100, 0.5)

        blocked = await s.client.put(f"/drones/{D1}/position",
                                     json={"x": 100, "y": 220, "z": 0}, headers=headers)
        assert blocked.status_code == 409 and "Circle Obstacle 1" in blocked.text
        placed = await s.client.put(f"/drones/{D1}/position",
                                    json={"x": 150, "y": 60, "z": 0}, headers=headers)
        assert placed.status_code == 200, placed.text
        assert placed.json()["position"]["x"] == pytest.approx(150, abs=0.5)
        assert placed.json()["status"] == "idle"
        flown = await s.client.put(f"/drones/{D1}/position",
                                   json={"x": 150, "y": 80, "z": 8}, headers=headers)
        assert flown.status_code == 200, flown.text
        assert flown.json()["position"]["z"] == pytest.approx(8, abs=0.5)
        assert flown.json()["status"] == "hovering"

        landed = await operator.post("/drones/land_all")
        assert not missing(LAND_ALL_KEYS, landed)
        assert all(not missing(LAND_ALL_DETAIL_KEYS, d) for d in landed["details"])
        assert (landed["drones_landed"], landed["drones_already_grounded"]) == (1, 1)
        first = next(d for d in landed["details"] if d["drone_id"] == D1)
        assert first["action"] == "landed" and first["previous_altitude"] > 7
        state = await operator.get(f"/drones/{D1}")
        assert state["position"]["z"] == pytest.approx(0, abs=0.3) and state["status"] == "idle"


async def test_drone_fields_change_at_once(tmp_path: Path) -> None:
    async with plat_server(tmp_path, _free()) as s:
        headers = {"X-API-Key": KEYS["operator"]}
        agent = PlatClient(s.client)
        assert await agent.get(f"/drones/{D1}/nearby/obstacles") == []
        for body, field in (({"max_speed": 5}, "max_speed"), ({"perceived_radius": 0},
                                                              "perceived_radius")):
            r = await s.client.put(f"/drones/{D1}", json=body, headers=headers)
            assert r.status_code == 422 and field in r.text, r.text
        r = await s.client.put(f"/drones/{D1}", headers=headers, json={
            "name": "Scout", "perceived_radius": 150, "task_radius": 15,
            "home_position": {"x": 110, "y": 90}})
        assert r.status_code == 200, r.text
        drone = r.json()
        assert (drone["name"], drone["perceived_radius"], drone["task_radius"]) == (
            "Scout", 150, 15)
        assert drone["home_position"]["x"] == pytest.approx(110, abs=0.5)
        seen = await agent.get(f"/drones/{D1}/nearby/obstacles")
        assert [o["id"] for o in seen] == ["0b0b0b01"]  # 110 m away, now within 150 m
