"""The reference's request history on `mavswarm serve`: every request recorded in the session
it acted on with the reference's fields; an agent reads only its own records (by its
X-Agent-ID), operators read and clear all."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.compat_fixtures import KEYS, PlatClient, plat_server

pytestmark = pytest.mark.mavsdk

RECORD_KEYS = {"request_id", "timestamp", "method", "path", "client_ip", "client_port",
               "client_privilege", "authentication_status", "session_id", "query_params",
               "user_agent", "agent_id", "status_code", "success", "duration", "error"}


async def test_requests_are_recorded_per_session_and_role(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as s:
        (sid,) = s.hub.sessions
        operator = PlatClient(s.client, KEYS["operator"])
        await s.client.get("/drones", headers={"X-Agent-ID": "alpha"})
        await s.client.get("/drones/d1d1d1d1", headers={"X-Agent-ID": "beta"})
        await s.client.get("/check/drone_group_distance", headers={"X-API-Key": KEYS["admin"]},
                           params=[("drone_ids", "d1d1d1d1"), ("drone_ids", "d2d2d2d2"),
                                   ("max_distance", "40")])
        refused = await s.client.get("/drones", headers={"X-API-Key": "guess"})
        assert refused.status_code == 401
        await s.client.get("/")  # never recorded

        records = await operator.get(f"/sessions/{sid}/request-history")
        assert all(set(r) == RECORD_KEYS for r in records)
        assert [r["path"] for r in records] == [
            "/drones", "/drones/d1d1d1d1", "/check/drone_group_distance", "/drones"]
        alpha, beta, check, bad = records
        assert (alpha["client_privilege"], alpha["agent_id"], alpha["authentication_status"]) \
            == ("AGENT", "alpha", "default_agent")
        assert beta["agent_id"] == "beta" and alpha["session_id"] == sid
        assert check["client_privilege"] == "ADMIN" and check["agent_id"] is None
        assert check["query_params"] == {"drone_ids": ["d1d1d1d1", "d2d2d2d2"],
                                         "max_distance": "40"}
        assert (bad["status_code"], bad["success"], bad["client_privilege"],
                bad["authentication_status"]) == (401, False, None, "invalid")

        mine = await PlatClient(s.client).http.get("/sessions/current/request-history",
                                                   headers={"X-Agent-ID": "alpha"})
        assert mine.status_code == 200
        assert {r["agent_id"] for r in mine.json()} == {"alpha"}
        assert (await s.client.get(f"/sessions/{sid}/request-history")).status_code == 403
        assert (await s.client.delete("/sessions/current/request-history")).status_code == 403
        cleared = await s.client.delete(f"/sessions/{sid}/request-history",
                                        headers={"X-API-Key": KEYS["operator"]})
        assert cleared.status_code == 200 and cleared.json()["cleared"] >= 7
        after = await operator.get(f"/sessions/{sid}/request-history")
        assert after == []  # the delete itself is not recorded


async def test_long_request_fields_are_cut(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as s:
        (sid,) = s.hub.sessions
        await s.client.get("/drones", params={"note": "x" * 5000},
                           headers={"User-Agent": "y" * 5000})
        (record,) = await PlatClient(s.client, KEYS["operator"]).get(
            f"/sessions/{sid}/request-history")
        assert record["query_params"]["note"] == "x" * 500
        assert record["user_agent"] == "y" * 500
