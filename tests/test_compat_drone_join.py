"""`POST /drones` and `DELETE /drones/{id}` on `mavswarm serve`: a drone created in a running
session joins the swarm as a new MAVLink vehicle that the gateway discovers over real UDP,
lists and flies; a deleted one stops speaking and is 404 afterwards. Operators and admins only,
never during a benchmark task; bad bodies are 422 and change nothing."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.compat_expectations import DRONE_KEYS
from tests.compat_fixtures import KEYS, PlatClient, plat_server, plat_world

pytestmark = pytest.mark.mavsdk

D1, D2 = "d1d1d1d1", "d2d2d2d2"
NEW = {"name": "Drone 3", "model": "quad", "position": {"x": 30, "y": 10},
       "battery_capacity": 5000, "max_speed": 10, "max_altitude": 100}


def _free() -> dict[str, Any]:
    world = plat_world()
    world["tasks"] = []
    return world


async def test_refused_to_agents_and_during_a_task(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as s:
        for path, method, body in (("/drones", "POST", NEW), (f"/drones/{D2}", "DELETE", None)):
            for headers in ({}, {"X-API-Key": KEYS["agent"]}):
                r = await s.client.request(method, path, json=body, headers=headers)
                assert r.status_code == 403, (path, r.text)
            r = await s.client.request(method, path, json=body,
                                       headers={"X-API-Key": KEYS["operator"]})
            assert r.status_code == 409 and "running benchmark task" in r.text, (path, r.text)
        (live,) = s.hub.sessions.values()
        assert live.swarm.n == 2 and len(await PlatClient(s.client).get("/drones")) == 2


async def test_a_created_drone_flies_and_a_deleted_one_is_gone(tmp_path: Path) -> None:
    async with plat_server(tmp_path, _free()) as s:
        operator = PlatClient(s.client, KEYS["operator"])
        headers = {"X-API-Key": KEYS["operator"]}
        (live,) = s.hub.sessions.values()
        for bad, field in (({**NEW, "max_speed": -1}, "max_speed"),
                           ({**NEW, "wings": 2}, "wings"),
                           ({k: v for k, v in NEW.items() if k != "name"}, "name"),
                           ({**NEW, "position": {"x": 1, "y": 2, "z": 500}}, "max_altitude")):
            r = await s.client.post("/drones", json=bad, headers=headers)
            assert r.status_code == 422 and field in r.text, (bad, r.text)
        r = await s.client.post("/drones", json={**NEW, "id": D1}, headers=headers)
        assert r.status_code == 409 and "taken" in r.text
        assert live.swarm.n == 2  # nothing changed

        drone = await operator.post("/drones", NEW)
        assert set(drone) == DRONE_KEYS - {"battery_volume"}
        new = drone["id"]
        position = drone["position"]
        assert (position["x"], position["y"], position["z"]) == pytest.approx((30, 10, 0),
                                                                               abs=0.05)
        assert drone["perceived_radius"] == 100 and drone["task_radius"] == 10
        assert live.swarm.n == 3 and live.gateway.drones[new].profile.system_id == 3
        listed = [d["id"] for d in await PlatClient(s.client).get("/drones")]
        assert listed == [D1, D2, new]
        took = await PlatClient(s.client).command(new, "take_off", altitude=6)
        assert took["status"] == "success", took
        state = await PlatClient(s.client).get(f"/drones/{new}")
        assert state["position"]["z"] == pytest.approx(6.0, abs=0.5)
        assert state["status"] == "hovering"
        z = live.swarm.recorder.trajectory(new)[:, 3]
        assert z.max() == pytest.approx(6.0, abs=0.5)

        deleted = await operator.http.delete(f"/drones/{new}", headers=headers)
        assert deleted.status_code == 200 and deleted.json()["id"] == new
        for path in (f"/drones/{new}", f"/drones/{new}/nearby"):
            r = await s.client.get(path)
            assert r.status_code == 404, (path, r.text)
        r = await s.client.delete(f"/drones/{new}", headers=headers)
        assert r.status_code == 404
        assert [d["id"] for d in await PlatClient(s.client).get("/drones")] == [D1, D2]
        assert [e.kind for e in live.swarm.recorder.events(new, kinds=["joined", "left"])] \
            == ["joined", "left"]
        r = await s.client.post("/drones", json={**NEW, "id": new}, headers=headers)
        assert r.status_code == 409 and "not reused" in r.text
        again = await operator.post("/drones", NEW)
        assert live.gateway.drones[again["id"]].profile.system_id == 4
        await operator.http.delete(f"/drones/{D1}", headers=headers)
        last = await s.client.delete(f"/drones/{D2}", headers=headers)
        assert last.status_code == 200
        r = await s.client.delete(f"/drones/{again['id']}", headers=headers)
        assert r.status_code == 409 and "last drone" in r.text
