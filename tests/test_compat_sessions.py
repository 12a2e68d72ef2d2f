"""An operator switches what a running `mavswarm serve` serves, as the reference's session
controller does: loads another session (a file on the server or the JSON in the body,
MultiUAV-Plat files converted), which starts its swarm and becomes current, or makes a live
session current again. Agents cannot; a refused load changes nothing."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.bench_fixtures import overcrowded, reference_session, small_session, write_json
from tests.cli_fixtures import ROOT
from tests.compat_fixtures import KEYS, PlatClient, plat_server
from tests.rest_fixtures import served

pytestmark = pytest.mark.mavsdk

EXAMPLE = ROOT.parent / "shared" / "sessions" / "Example_Session_Area_Search.json"


async def test_operator_loads_sessions_and_switches_between_them(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as s:
        (first,) = s.hub.sessions
        keyless, operator = PlatClient(s.client), PlatClient(s.client, KEYS["operator"])
        bound = PlatClient(s.client, KEYS["agent"])  # a key bound to the first session
        before = {d["name"] for d in await keyless.get("/drones")}
        second = reference_session()
        path = write_json(tmp_path / "second.json", second)
        s.hub.session_folders.allow_folder(tmp_path)  # as `serve --session-dir tmp_path`
        denied = await s.client.post("/sessions/load", json={"path": str(path)})
        assert denied.status_code == 403 and list(s.hub.sessions) == [first]

        loaded = await operator.post("/sessions/load", {"path": str(path)})
        assert loaded["id"] == second["id"] and loaded["current"] == second["id"]
        assert any("size label" in note for note in loaded["notes"])
        assert {d["id"] for d in await keyless.get("/drones")} == \
            {d["id"] for d in second["drones"]}  # the keyless agent follows the current one
        assert {d["name"] for d in await bound.get("/drones")} == before
        current = await operator.get("/sessions/current")
        assert current["id"] == second["id"] and current["status"] == "active"
        assert (await operator.get("/sessions/current", session=first))["status"] == "inactive"
        free = await keyless.get("/sessions/current/tasks/next")  # a world without tasks
        assert free["id"] == "free-flight"
        drone = second["drones"][0]["id"]
        took = await keyless.command(drone, "take_off", altitude=6)
        assert took["status"] == "success", took

        third = small_session(["takeoff_hold"])
        body = await operator.post("/sessions/load", {"session": third})
        assert body["current"] == third["id"] and body["task"] == third["tasks"][0]["id"]
        assert len(s.hub.sessions) == 3
        back = await operator.post(f"/sessions/{first}/set-current")
        assert back["current"] == first
        assert {d["name"] for d in await keyless.get("/drones")} == before
        refused = await s.client.post(f"/sessions/{second['id']}/set-current")
        assert refused.status_code == 403 and s.hub.current() == first


async def test_bad_loads_are_refused_and_change_nothing(tmp_path: Path) -> None:
    unloadable = reference_session()
    unloadable["id"] = "unloadable"
    unloadable["drones"][0]["position"]["z"] = -5.0
    unflyable = overcrowded(reference_session())
    unflyable["id"] = "unflyable"
    broken = tmp_path / "broken.json"
    broken.write_text('{"drones": [', encoding="utf-8")
    async with plat_server(tmp_path) as s:
        (first,) = s.hub.sessions
        s.hub.session_folders.allow_folder(tmp_path)
        operator = PlatClient(s.client, KEYS["operator"])
        cases = [
            ({"path": str(tmp_path / "missing.json")}, 404, "no such session file"),
            ({"path": str(broken)}, 422, "not valid JSON"),
            ({"path": ""}, 422, "path"),
            ({"path": str(broken), "session": {}}, 422, "either 'path' or 'session'"),
            ({"session": unloadable}, 422, "position.z must be between 0"),
            (unflyable, 422, "cannot start"),
            ({"name": "no drones"}, 422, "the body must be"),
            ([1, 2, 3], 422, "the body must be"),
            (json.loads(s.path.read_text()), 409, "already live"),
        ]
        for body, status, words in cases:
            answer = await s.client.post("/sessions/load", json=body,
                                         headers=operator.headers)
            assert answer.status_code == status, (body, answer.text)
            assert words in answer.json()["detail"], (words, answer.text)
            assert list(s.hub.sessions) == [first] and s.hub.current() == first
        for raw in (b"{not json", b'{"session": NaN}', b"\xff\xfe", b"[" * 100_000):
            garbage = await s.client.post("/sessions/load", content=raw,
                                          headers=operator.headers)
            assert garbage.status_code == 422, (raw[:20], garbage.text)
            assert list(s.hub.sessions) == [first]
        unknown = await s.client.post("/sessions/nope/set-current", headers=operator.headers)
        assert unknown.status_code == 404 and s.hub.current() == first


@pytest.mark.skipif(not EXAMPLE.is_file(), reason="needs the reference example files in ../shared")
async def test_the_reference_example_session_loads_into_a_running_server(tmp_path: Path) -> None:
    async with plat_server(tmp_path) as s:
        operator = PlatClient(s.client, KEYS["operator"])
        example = json.loads(EXAMPLE.read_text(encoding="utf-8"))
        loaded = await operator.post("/sessions/load", example)  # the file's JSON as the body
        assert loaded["drones"] == len(example["drones"]) and loaded["current"] == loaded["id"]
        drones = await PlatClient(s.client).get("/drones")
        assert {d["name"] for d in drones} == {d["name"] for d in example["drones"]}


async def test_health_needs_no_key_and_tells_nothing_about_the_world() -> None:
    async with served() as s:  # not --open: other routes need a key
        assert (await s.client.get("/drones")).status_code == 401
        for path in ("/", "/health", "/version"):
            answer = await s.client.get(path)
            assert answer.status_code == 200, path
            text = answer.text
            assert s.live.id not in text and "drone" not in text.lower(), text
        assert (await s.client.get("/health")).json() == {
            "status": "online", "message": "mavswarm REST API is running"}
        loading = await s.client.post("/sessions/load", json={"session": small_session([])},
                                      headers={"X-API-Key": "key-admin"})
        assert loading.status_code == 501  # this hub was built without a session starter
        public = set((await s.client.get("/openapi.json")).json()["paths"])
        assert {"/health", "/targets/type/{target_type}", "/obstacles/path_collision",
                "/sessions/current/task-progress"} <= public
        assert not public & {"/sessions/load", "/sessions/{session_id}/set-current",
                             "/sessions/current/data", "/sessions/{session_id}/data"}
        staff = (await s.client.get("/openapi.json", headers={"X-API-Key": "key-operator"}))
        assert "/sessions/load" in staff.json()["paths"]
