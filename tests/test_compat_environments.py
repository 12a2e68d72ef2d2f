"""The reference's environment routes on `mavswarm serve`: list, get, create, update, delete
and set-current; the current environment's wind drives the vehicles; agents read, never write;
writes refused while a benchmark task runs; bodies validated (422 naming the field)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.compat_expectations import ENVIRONMENT_KEYS, missing
from tests.compat_fixtures import KEYS, PlatClient, plat_server, plat_world

pytestmark = pytest.mark.mavsdk


def _free() -> dict[str, Any]:
    world = plat_world()
    world["tasks"] = []
    return world


async def test_environments_for_staff_and_their_wind_on_the_vehicles(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as s:
        r = await s.client.post("/environments", json={"name": "Gale"},
                                headers={"X-API-Key": KEYS["operator"]})
        assert r.status_code == 409  # a benchmark task runs
        assert (await s.client.get("/environments")).status_code == 403
    async with plat_server(tmp_path, _free()) as s:
        (sid,) = s.hub.sessions
        operator, agent = PlatClient(s.client, KEYS["operator"]), PlatClient(s.client)
        headers = {"X-API-Key": KEYS["operator"]}
        (calm,) = await operator.get("/environments")
        assert calm["id"] == "e0e0e0e0" and not missing(ENVIRONMENT_KEYS, calm)
        assert (await agent.get("/environments/e0e0e0e0"))["name"] == "Calm"
        for body, field in (({"name": "x", "wind_direction": "up"}, "wind_direction"),
                            ({"name": "x", "humidity": 120}, "humidity"),
                            ({"weather": "rain"}, "name")):
            r = await s.client.post("/environments", json=body, headers=headers)
            assert r.status_code == 422 and field in r.text, r.text
        assert (await s.client.post("/environments", json={"name": "Gale"})).status_code == 403
        gale = await operator.post("/environments", {"name": "Gale", "weather": "windy",
                                                     "wind_speed": 8, "wind_direction": "west"})
        assert not missing(ENVIRONMENT_KEYS, gale) and gale["pressure"] == 1013.25
        assert len(await operator.get("/environments")) == 2
        wind = s.hub.sessions[sid].swarm.fleet.dyn.wind_m_s
        assert wind.tolist() == pytest.approx([0.0, 0.0])
        await operator.post(f"/environments/{gale['id']}/set-current")
        assert (await operator.get("/environments/current"))["id"] == gale["id"]
        wind = s.hub.sessions[sid].swarm.fleet.dyn.wind_m_s
        assert wind.tolist() == pytest.approx([8.0, 0.0], abs=1e-9)  # from the west: east
        changed = await s.client.put(f"/environments/{gale['id']}", headers=headers,
                                     json={"wind_direction": "south"})
        assert changed.status_code == 200 and changed.json()["wind_speed"] == 8
        wind = s.hub.sessions[sid].swarm.fleet.dyn.wind_m_s
        assert wind.tolist() == pytest.approx([0.0, 8.0], abs=1e-9)
        r = await s.client.delete(f"/environments/{gale['id']}", headers=headers)
        assert r.status_code == 409 and "current" in r.text
        gone = await s.client.delete("/environments/e0e0e0e0", headers=headers)
        assert gone.status_code == 200
        assert [e["id"] for e in await operator.get("/environments")] == [gale["id"]]
        assert (await s.client.get("/environments/e0e0e0e0")).status_code == 404
