"""The REST API with roles, served in-process (httpx ASGITransport) over a real stepped swarm:
every route under every role, authentication errors, an agent flying through the tools route,
and nothing hidden reaching an agent."""

from __future__ import annotations

import json

import pytest

from benchmark.server import Hub
from tests.rest_fixtures import as_role, served

pytestmark = pytest.mark.mavsdk

ALL_OK = {"agent": 200, "operator": 200, "admin": 200}
ACTORS = {"agent": 200, "operator": 403, "admin": 200}
FLYERS = {"agent": 200, "operator": 409, "admin": 200}  # an operator flies only without a task

# (method, path, expected status per role); {s} = the session id, {d} = a drone id.
ROUTES: list[tuple[str, str, dict[str, int]]] = [
    ("GET", "/sessions", {"agent": 403, "operator": 200, "admin": 200}),
    ("GET", "/sessions/{s}", ALL_OK),
    ("GET", "/sessions/{s}/drones", ALL_OK),
    ("GET", "/sessions/{s}/drones/{d}", ALL_OK),
    ("GET", "/sessions/{s}/task", ALL_OK),
    ("GET", "/sessions/{s}/tools", ALL_OK),
    ("POST", "/sessions/{s}/tools/list_drones", ACTORS),
    ("GET", "/sessions/{s}/nearby/{d}", ALL_OK),
    ("GET", "/check/sessions/{s}/task", {"agent": 403, "operator": 403, "admin": 200}),
    ("GET", "/drones", ALL_OK),
    ("GET", "/drones/{d}", ALL_OK),
    ("POST", "/drones/{d}/command/rotate?heading=90", FLYERS),
    ("GET", "/drones/{d}/nearby", ALL_OK),
    ("GET", "/drones/{d}/nearby/targets", ALL_OK),
    ("GET", "/drones/{d}/nearby/clouds", {"agent": 404, "operator": 404, "admin": 404}),
    ("GET", "/sessions/current/tasks/next", ALL_OK),
    ("GET", "/sessions/current", ALL_OK),
    ("GET", "/sessions/current/tasks", ALL_OK),
    ("GET", "/environments/current", ALL_OK),
    ("GET", "/targets/nope", {"agent": 404, "operator": 404, "admin": 404}),
    ("GET", "/obstacles/nope", {"agent": 404, "operator": 404, "admin": 404}),
    ("POST", "/drones/{d}/command", {"agent": 422, "operator": 422, "admin": 422}),
    ("GET", "/sessions/nope", {"agent": 403, "operator": 404, "admin": 404}),
    ("GET", "/sessions/{s}/drones/nope", {"agent": 404, "operator": 404, "admin": 404}),
    ("POST", "/sessions/{s}/tools/teleport", {"agent": 404, "operator": 403, "admin": 404}),
    ("POST", "/drones/{d}/command/fly_away", {"agent": 404, "operator": 409, "admin": 404}),
]


async def test_every_route_under_every_role_and_without_a_key() -> None:
    async with served() as s:
        client, hub, data = s.client, s.hub, s.data
        (sid,) = hub.sessions
        drone = data["drones"][0]["id"]
        problems = []
        for method, template, expected in ROUTES:
            path = template.format(s=sid, d=drone)
            for role, status in expected.items():
                r = await client.request(method, path, headers=as_role(role))
                if r.status_code != status:
                    problems.append(f"{method} {path} as {role}: {r.status_code} {r.text[:200]}")
            r = await client.request(method, path)
            if r.status_code != 401 or "missing API key" not in r.json()["detail"]:
                problems.append(f"{method} {path} without a key: {r.status_code}")
        assert not problems, "\n".join(problems)
        assert (await client.get("/docs")).status_code == 200
        spec = (await client.get("/openapi.json")).json()
        assert "/sessions/{session_id}/tools/{name}" in spec["paths"]


async def test_auth_errors_say_what_is_wrong() -> None:
    async with served() as s:
        client, hub = s.client, s.hub
        (sid,) = hub.sessions
        r = await client.get(f"/sessions/{sid}", headers={"X-API-Key": "guess"})
        assert r.status_code == 401 and r.json()["detail"] == (
            "unknown API key in the X-API-Key header")
        r = await client.get("/sessions", headers=as_role("agent"))
        assert r.status_code == 403
        assert r.json()["detail"] == ("role 'agent' may not use this route; it needs one of: "
                                      "operator, admin")
        r = await client.get("/sessions/other/task", headers=as_role("agent"))
        assert r.status_code == 403 and f"bound to session {sid!r}" in r.json()["detail"]
        r = await client.post(f"/sessions/{sid}/tools/take_off", headers=as_role("operator"))
        assert r.status_code == 403 and "'operator'" in r.json()["detail"]


async def test_views_differ_by_role() -> None:
    async with served() as s:
        client, hub, data = s.client, s.hub, s.data
        (sid,) = hub.sessions
        agent = (await client.get(f"/sessions/{sid}", headers=as_role("agent"))).json()
        operator = (await client.get(f"/sessions/{sid}", headers=as_role("operator"))).json()
        admin = (await client.get(f"/sessions/{sid}", headers=as_role("admin"))).json()
        assert agent["task"] == {"id": "t01", "text": data["tasks"][0]["text"]}
        assert "targets" not in agent and "obstacles" not in agent and "data" not in agent
        assert len(operator["targets"]) == len(data["targets"]) and "checks" not in operator["task"]
        assert admin["task"]["checks"] == data["tasks"][0]["checks"]
        assert admin["task"]["oracle"] == data["tasks"][0]["oracle"]
        assert admin["data"]["targets"] == data["targets"]
        task = (await client.get(f"/sessions/{sid}/task", headers=as_role("agent"))).json()
        assert set(task) == {"id", "text"}
        listed = (await client.get("/sessions", headers=as_role("operator"))).json()
        assert [s["id"] for s in listed] == [sid]


async def test_agent_takes_off_through_the_tools_route() -> None:
    async with served() as s:
        client, hub, data = s.client, s.hub, s.data
        (sid,) = hub.sessions
        op = data["tasks"][0]["oracle"][0][0]
        drone, altitude = op["drone"], op["altitude_m"]
        r = await client.post(f"/sessions/{sid}/tools/take_off", headers=as_role("agent"),
                              json={"drone_id": drone, "altitude_m": altitude})
        assert r.status_code == 200 and r.json()["status"] == "ok", r.text
        assert abs(r.json()["state"]["altitude_m"] - altitude) < 1.0
        state = (await client.get(f"/drones/{drone}", headers=as_role("agent"))).json()
        assert state["status"] == "hovering" and abs(state["position"]["z"] - altitude) < 1.0
        bad = await client.post(f"/sessions/{sid}/tools/take_off", headers=as_role("agent"),
                                json={"drone_id": drone, "altitude_m": "high"})
        assert bad.json() == {"status": "error",
                              "message": "take_off: altitude_m must be a number, got 'high'"}
        broken = await client.post(f"/sessions/{sid}/tools/land", headers=as_role("agent"),
                                   content=b"{drone_id: ")
        assert "not valid JSON" in broken.json()["message"]
        hub.sessions[sid].tools.finish("done")
        check = (await client.get(f"/check/sessions/{sid}/task", headers=as_role("admin"))).json()
        assert check["passed"] is True and check["leaves"], check
        assert hub.sessions[sid].tools.tool_calls == 1  # only the take-off was executed


async def test_compat_commands_take_query_parameters() -> None:
    async with served() as s:
        client, data = s.client, s.data
        drone = data["drones"][1]["id"]
        r = await client.post(f"/drones/{drone}/command/take_off?altitude=6",
                              headers=as_role("agent"))
        body = r.json()
        assert r.status_code == 200 and body["status"] == "success", body
        assert body["command"] == "take_off" and len(body["command_id"]) == 8
        r = await client.post(f"/drones/{drone}/command/move_towards?distance=5",
                              headers=as_role("agent"))
        assert r.status_code == 400 and "Direction must be specified" in r.json()["detail"]
        r = await client.post(f"/drones/{drone}/command/change_altitude?altitude=lots",
                              headers=as_role("agent"))
        assert r.status_code == 422
        assert r.json()["detail"] == "parameter 'altitude' must be a number, got 'lots'"
        r = await client.post(f"/drones/{drone}/command/move_along_path", headers=as_role("agent"),
                              content=b"[{x: 1")
        assert r.status_code == 422 and "not valid JSON" in r.json()["detail"]
        r = await client.post(f"/drones/{drone}/command/land", headers=as_role("agent"))
        assert r.json()["status"] == "success", r.json()
        drones = (await client.get("/drones", headers=as_role("operator"))).json()
        assert {d["id"] for d in drones} == {d["id"] for d in data["drones"]}


async def test_no_agent_response_reveals_hidden_data() -> None:
    async with served() as s:
        client, hub, data = s.client, s.hub, s.data
        (sid,) = hub.sessions
        texts: list[str] = []
        perceived: set[str] = set()
        for method, template, _ in ROUTES:
            for drone in data["drones"]:
                path = template.format(s=sid, d=drone["id"])
                r = await client.request(method, path, headers=as_role("agent"))
                texts.append(r.text)
                if "/nearby" in path and r.status_code == 200:
                    seen = r.json()
                    if isinstance(seen, list):  # /drones/{d}/nearby/<kind>
                        perceived |= {e["id"] for e in seen if e.get("kind") != "drone"}
                        continue
                    payload = seen.get("data", seen)
                    perceived |= {e["id"] for k in ("targets", "obstacles")
                                  for e in payload.get(k, [])}
        hidden = {e["id"] for k in ("targets", "obstacles") for e in data[k]} - perceived
        assert hidden, "the scenario should have entities outside every drone's perception"
        everything = "\n".join(texts)
        assert json.loads(texts[0])  # the scan saw real payloads
        for word in ("checks", "oracle", *sorted(hidden)):
            assert word not in everything, word
        # The same scan over an admin's view does find them: the scan can fail.
        admin = (await client.get(f"/sessions/{sid}", headers=as_role("admin"))).text
        assert "checks" in admin and all(h in admin for h in hidden)


def test_hub_rejects_bad_keys() -> None:
    hub = Hub()
    with pytest.raises(ValueError, match=r"role: expected one of .* got 'root'"):
        hub.add_key("k", "root")
    with pytest.raises(ValueError, match="session_id: an agent key needs a session"):
        hub.add_key("k", "agent", "s1")
    with pytest.raises(ValueError, match="only agent keys are bound"):
        hub.add_key("k", "admin", "s1")
    with pytest.raises(ValueError, match="key: expected a non-empty string"):
        hub.add_key(" ", "admin")
    hub.add_key("k", "admin")
    with pytest.raises(ValueError, match="already registered"):
        hub.add_key("k", "operator")
