"""The reference's session lifecycle and screenshot routes on `mavswarm serve`: creating a
session from the reference's layout (new id, or the path's), resetting a session's histories,
and the 2D map as a PNG for operators and admins only."""

from __future__ import annotations

import struct
import zlib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from benchmark.server.compat.screenshot import OBSTACLE, STATION
from tests.compat_fixtures import KEYS, PlatClient, plat_server, plat_world

pytestmark = pytest.mark.mavsdk

D1 = "d1d1d1d1"


def _free() -> dict[str, Any]:
    world = plat_world()
    world["tasks"] = []
    return world


def _decode_png(data: bytes) -> np.ndarray:
    """The pixels of an 8-bit RGB PNG whose rows all use filter 0 (as the server writes)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    at, chunks = 8, dict[bytes, bytes]()
    while at < len(data):
        (length,) = struct.unpack(">I", data[at:at + 4])
        kind, body = data[at + 4:at + 8], data[at + 8:at + 8 + length]
        (crc,) = struct.unpack(">I", data[at + 8 + length:at + 12 + length])
        assert crc == zlib.crc32(kind + body) & 0xFFFFFFFF
        chunks[kind] = chunks.get(kind, b"") + body
        at += 12 + length
    width, height, depth, colour = struct.unpack(">IIBB", chunks[b"IHDR"][:10])
    assert (depth, colour) == (8, 2)
    rows = np.frombuffer(zlib.decompress(chunks[b"IDAT"]), np.uint8).reshape(height, -1)
    assert not rows[:, 0].any()
    return rows[:, 1:].reshape(height, width, 3)


async def test_screenshot_is_the_map_for_staff_only(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as s:
        (sid,) = s.hub.sessions
        for path in ("/sessions/current/screenshot", f"/sessions/{sid}/screenshot"):
            assert (await s.client.get(path)).status_code == 403
        headers = {"X-API-Key": KEYS["operator"]}
        r = await s.client.get("/sessions/current/screenshot", params={"width": 600},
                               headers=headers)
        assert r.status_code == 200 and r.headers["content-type"] == "image/png"
        image = _decode_png(r.content)
        assert image.shape == (500, 600, 3)  # the 600 x 500 m canvas, 1 px per metre
        assert tuple(image[500 - 220, 100]) == OBSTACLE  # Circle Obstacle 1 at (100, 220)
        assert tuple(image[500 - 95, 135]) == STATION  # Waypoint 1 at (130, 100)
        r = await s.client.get(f"/sessions/{sid}/screenshot", params={"format": "svg"},
                               headers=headers)
        assert r.status_code == 422 and "format" in r.text


async def test_sessions_created_from_the_reference_layout_and_reset(tmp_path: Path) -> None:
    async with plat_server(tmp_path, _free()) as s:
        (first,) = s.hub.sessions
        operator = PlatClient(s.client, KEYS["operator"])
        headers = {"X-API-Key": KEYS["operator"]}
        assert (await s.client.post("/sessions", json=plat_world())).status_code == 403
        for body, path, status, words in (
                ({"drones": []}, "/sessions", 422, "name"),
                (plat_world(), "/sessions/current", 422, "word of the session routes"),
                (plat_world(), f"/sessions/{first}", 409, "not overwritten")):
            r = await s.client.post(path, json=body, headers=headers)
            assert r.status_code == status and words in r.text, r.text
        assert list(s.hub.sessions) == [first]

        took = await operator.command(D1, "take_off", altitude=5)
        assert took["status"] == "success"
        assert len(await operator.get(f"/sessions/{first}/command-history")) == 1
        reset = await operator.post("/sessions/current/reset")
        assert reset["id"] == first
        assert await operator.get(f"/sessions/{first}/command-history") == []
        assert (await operator.get(f"/drones/{D1}"))["position"]["z"] > 4  # entities kept

        r = await s.client.put(f"/sessions/{first}", json={"status": "inactive"},
                               headers=headers)
        assert r.status_code == 422 and "status" in r.text
        renamed = await s.client.put(f"/sessions/{first}", headers=headers,
                                     json={"name": "Patrol B", "description": "second try"})
        assert renamed.status_code == 200 and renamed.json()["name"] == "Patrol B"
        assert (await operator.get("/sessions/current"))["description"] == "second try"

        made = await operator.post("/sessions", plat_world())
        assert len(made["id"]) == 8 and made["id"] != first and made["status"] == "active"
        assert s.hub.current() == made["id"] and made["name"] == "Compat Patrol"
        named = await operator.post("/sessions/abcd1234", plat_world())
        assert named["id"] == "abcd1234" and len(s.hub.sessions) == 3
        r = await s.client.post("/sessions/abcd1234/reset", headers=headers)
        assert r.status_code == 409  # its benchmark task runs
        r = await s.client.put("/sessions/abcd1234", json={"name": "x"}, headers=headers)
        assert r.status_code == 409


async def test_a_deleted_session_stops_and_is_gone(tmp_path: Path) -> None:
    async with plat_server(tmp_path, _free()) as s:
        (first,) = s.hub.sessions
        headers = {"X-API-Key": KEYS["operator"]}
        operator = PlatClient(s.client, KEYS["operator"])
        busy = await operator.post("/sessions/abcd1234", plat_world())
        assert s.hub.current() == busy["id"]
        for key in (None, KEYS["agent"]):
            r = await s.client.delete(f"/sessions/{first}",
                                      headers={"X-API-Key": key} if key else {})
            assert r.status_code == 403, r.text
        r = await s.client.delete("/sessions/abcd1234", headers=headers)
        assert r.status_code == 409 and "running benchmark task" in r.text
        r = await s.client.delete("/sessions/nope", headers=headers)
        assert r.status_code == 404
        live = s.hub.sessions[first]
        deleted = await s.client.delete(f"/sessions/{first}", headers=headers)
        assert deleted.status_code == 200, deleted.text
        assert deleted.json()["sessions"] == ["abcd1234"]
        assert list(s.hub.sessions) == ["abcd1234"] and s.hub.current() == "abcd1234"
        assert not live.swarm.endpoints[0].is_open  # its swarm was shut down
        r = await s.client.get(f"/sessions/{first}/command-history", headers=headers)
        assert r.status_code == 404
        r = await s.client.delete(f"/sessions/{first}", headers=headers)
        assert r.status_code == 404
