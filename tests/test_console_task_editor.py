"""The scenario editor's task and template routes over a real socket (uvicorn, httpx): template
files listed, read and validated (the field to blame named), a template's tasks drawn on the
edited world (entities, check tree, deterministic by seed), every task re-checked after the
world is edited (the failing leaf named), a task proved by the oracle on a sandbox swarm, and
templates saved into the editor's save folder. Agents' keys get 403 on every one of them."""

from __future__ import annotations

import asyncio
import json
import os
import subprocess
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from benchmark.authoring.session_file import session_from_dict
from benchmark.scoring.validators import parse_tree
from console.app import ConsoleState, create_console_app
from console.auth import ConsoleAuth
from console.task_editor import BUILT_IN_DIR
from tests.asgi_fixtures import listening
from tests.cli_fixtures import MAVSWARM, ROOT, read_until
from tests.ports import unused_tcp_port

KEYS = {"op-key": "operator", "admin-key": "admin", "agent-key": "agent"}
OPERATOR = {"X-API-Key": "op-key"}
PHOTO = (BUILT_IN_DIR / "photo_at_point.json").read_text()
WORLD_FILE = ROOT / "benchmark/sessions/area_search-easy-1.json"
ROUTES: list[tuple[str, str, dict[str, Any] | None]] = [
          ("GET", "/api/editor/templates", None),
          ("GET", "/api/editor/templates/checkpoint", None),
          ("POST", "/api/editor/templates/validate", {"text": PHOTO}),
          ("POST", "/api/editor/templates/instantiate", {"session": {}, "text": PHOTO}),
          ("POST", "/api/editor/templates/save", {"text": PHOTO}),
          ("POST", "/api/editor/tasks/recheck", {"session": {}}),
          ("POST", "/api/editor/proofs", {"session": {}, "task_id": "t01"}),
          ("GET", "/api/editor/proofs/proof-1", None)]


def _world() -> dict[str, Any]:
    data = json.loads(WORLD_FILE.read_text())
    return {**data, "id": "editor-world", "tasks": []}


@pytest.fixture
async def console(tmp_path: Path) -> AsyncIterator[tuple[httpx.AsyncClient, Path]]:
    state = ConsoleState(ConsoleAuth(KEYS.get), editor_root=tmp_path)
    try:
        async with listening(create_console_app(state)) as url, httpx.AsyncClient(
                base_url=url, headers=OPERATOR, timeout=120) as client:
            yield client, tmp_path
    finally:
        await state.aclose()


async def _drawn(client: httpx.AsyncClient, world: dict[str, Any], text: str = PHOTO,
                 count: int = 2, seed: int = 1) -> dict[str, Any]:
    answer = await client.post("/api/editor/templates/instantiate",
                               json={"session": world, "text": text, "count": count,
                                     "seed": seed})
    assert answer.status_code == 200, answer.text
    return dict(answer.json())


@pytest.mark.parametrize(("method", "path", "body"), ROUTES)
async def test_agents_and_strangers_are_refused_every_route(
        console: tuple[httpx.AsyncClient, Path], method: str, path: str,
        body: dict[str, Any] | None) -> None:
    client, folder = console
    for headers, status in (({"X-API-Key": "agent-key"}, 403), ({"X-API-Key": "nobody"}, 401),
                            ({"X-API-Key": ""}, 401)):
        answer = await client.request(method, path, json=body, headers=headers)
        assert answer.status_code == status, (headers, answer.text)
        assert "templates" not in answer.text.replace("/api/editor/templates", "")
        assert "checks" not in answer.text
    assert not (folder / "templates").exists()


async def test_templates_are_listed_and_read_by_id(console: tuple[httpx.AsyncClient, Path]
                                                  ) -> None:
    client, _ = console
    listed = (await client.get("/api/editor/templates",
                               headers={"X-API-Key": "admin-key"})).json()["templates"]
    files = sorted(BUILT_IN_DIR.glob("*.json"))
    assert [t["file"] for t in listed] == [p.name for p in files] and len(listed) >= 25
    assert all(t["source"] == "built-in" and t["category"] and "error" not in t for t in listed)
    one = (await client.get("/api/editor/templates/checkpoint")).json()
    assert one["text"] == (BUILT_IN_DIR / "checkpoint.json").read_text()
    for ident in ("no_such_template", "..%2F..%2Fpyproject", "checkpoint.json"):
        missing = await client.get(f"/api/editor/templates/{ident}")
        assert missing.status_code == 404, ident
        if "%2F" not in ident:  # a path is no template's id: it matches no route at all
            assert "GET /api/editor/templates lists them" in missing.json()["detail"]


@pytest.mark.parametrize(("edit", "field", "reason"), [
    (lambda t: t.replace('"max": 30', '"max": 3'), "values[0]", "max 3 < min 15"),
    (lambda t: t.replace("drone_has_taken_photo", "drone_took_photo"), "checks[1].endpoint",
     "unknown endpoint"),
    (lambda t: t.replace('"tolerance": 3.0', '"tolerance": -3.0'),
     "checks[0].parameters.tolerance", "must be >= 0"),
    (lambda t: t.replace('"category": "search"', '"category": "sightseeing"'), "category",
     "is not one of"),
    (lambda t: t[:-3], "(file)", "not JSON"),
    (lambda t: t.replace('"min": 15, "max": 30', '"min": 15, "max": 1e999'), "values[0].max",
     "not a finite number"),
    (lambda t: t.replace('"min": 15, "max": 30', '"min": -Infinity, "max": 30'),
     "values[0].min", "not a finite number"),
    (lambda t: t.replace('{"name": "p", "kind": "point"}',
                         '{"name": "p", "kind": "hook", "call": "os:system"}'),
     "values[1].call", "not a built-in hook"),
    (lambda t: t.replace('{"name": "p", "kind": "point"}',
                         '{"name": "p", "kind": "hook", '
                         '"call": "benchmark.authoring.templates.base:all_of"}'),
     "values[1].call", "benchmark.authoring.templates.search:sweep_length"),
])
async def test_a_bad_template_is_refused_naming_the_field(
        console: tuple[httpx.AsyncClient, Path], edit: Any, field: str, reason: str) -> None:
    client, folder = console
    text = edit(PHOTO)
    answer = await client.post("/api/editor/templates/validate", json={"text": text})
    assert answer.status_code == 422
    body = answer.json()
    assert body["ok"] is False and body["field"] == field and reason in body["error"]
    drawn = await client.post("/api/editor/templates/instantiate",
                              json={"session": _world(), "text": text})
    saved = await client.post("/api/editor/templates/save", json={"text": text})
    assert drawn.status_code == saved.status_code == 422
    assert drawn.json()["field"] == saved.json()["field"] == field
    assert not (folder / "templates").exists()
    good = await client.post("/api/editor/templates/validate", json={"text": PHOTO})
    assert good.status_code == 200 and good.json()["id"] == "photo_at_point"


async def test_bodies_are_bounded_and_validated(console: tuple[httpx.AsyncClient, Path]
                                               ) -> None:
    client, _ = console
    huge = await client.post("/api/editor/templates/validate", json={"text": "x" * 20_000})
    assert huge.status_code in (413, 422) and "text" in huge.text
    for body in ({"text": PHOTO, "extra": 1}, {"session": _world(), "text": PHOTO, "count": 0},
                 {"session": _world(), "text": PHOTO, "count": 500}):
        path = ("/api/editor/templates/validate" if "extra" in body
                else "/api/editor/templates/instantiate")
        answer = await client.post(path, json=body)
        assert answer.status_code == 422, body
    many = await client.post("/api/editor/proofs",
                             content=b"[" * 100 + b"]" * 100,
                             headers={"Content-Type": "application/json"})
    assert many.status_code in (413, 422)


async def test_tasks_are_drawn_on_the_world_with_entities_and_tree(
        console: tuple[httpx.AsyncClient, Path]) -> None:
    client, _ = console
    world = _world()
    world["tasks"] = [{"id": "t01", "text": "already here", "checks": {"logic": "and", "checks": [
        {"endpoint": "drone_is_on_ground", "parameters": {"drone_id": "d1"}}]},
        "budget": {"tool_calls": 10, "sim_time_s": 60}}]
    drawn = await _drawn(client, world, count=3)
    assert drawn["template"] == "photo_at_point" and len(drawn["tasks"]) == 3
    assert [d["task"]["id"] for d in drawn["tasks"]] == ["t02", "t03", "t04"]
    scenario = session_from_dict({**world, "tasks": []}, source="w").scenario
    drones = {v.id for v in scenario.vehicles}
    for item in drawn["tasks"]:
        task, entities = item["task"], item["entities"]
        assert entities["drones"] and set(entities["drones"]) <= drones
        assert entities["drones"][0] in task["checks"]["checks"][0]["parameters"]["drone_id"]
        x, y = entities["points"][0]
        assert f"({x:.0f}, {y:.0f})" in task["text"]
        assert item["tree"]["logic"] == "and"
        assert [c["endpoint"] for c in item["tree"]["checks"]] == [
            "drone_has_visited_position", "drone_has_taken_photo"]
        parse_tree(task["checks"], scenario)
        assert item["check"] == {"solvable": True, "leaf": None, "endpoint": None,
                                 "reason": None}
    again = await _drawn(client, world, count=3)
    assert again == drawn
    other = await _drawn(client, world, count=3, seed=2)
    assert other["tasks"] != drawn["tasks"]


async def test_a_template_the_world_cannot_take_is_answered_with_why(
        console: tuple[httpx.AsyncClient, Path]) -> None:
    client, _ = console
    follow = (BUILT_IN_DIR / "follow_moving_target.json").read_text()
    answer = await client.post("/api/editor/templates/instantiate",
                               json={"session": _world(), "text": follow})
    assert answer.status_code == 422
    assert "moving target" in answer.json()["error"]
    high = PHOTO.replace('"min": 15, "max": 30', '"min": 500, "max": 600')
    drawn = await _drawn(client, _world(), text=high, count=1)
    check = drawn["tasks"][0]["check"]
    assert not check["solvable"] and check["leaf"] == "checks[0]"
    assert "above" in check["reason"] and "maximum altitude" in check["reason"]
    typo = PHOTO.replace("Fly {drone_1_name}", "Fly {drone_one_name}")
    noted = await _drawn(client, _world(), text=typo, count=1)
    assert "placeholders left unfilled in the phrasings: {drone_one_name}" in noted["note"]
    badly = PHOTO.replace('"steps": 3', '"steps": "{p}"')
    refused = await client.post("/api/editor/templates/instantiate",
                                json={"session": _world(), "text": badly})
    assert refused.status_code == 422
    assert "does not fill in" in refused.json()["error"] and "(" in refused.json()["error"]
    broken = await client.post("/api/editor/templates/instantiate",
                               json={"session": {**_world(), "drones": "many"}, "text": PHOTO})
    assert broken.status_code == 422 and "drones" in broken.json()["error"]


async def test_every_task_is_rechecked_after_the_world_is_edited(
        console: tuple[httpx.AsyncClient, Path]) -> None:
    client, _ = console
    world = _world()
    world["tasks"] = [d["task"] for d in (await _drawn(client, world, count=2))["tasks"]]
    fine = (await client.post("/api/editor/tasks/recheck", json={"session": world})).json()
    assert fine["solvable"] == fine["total"] == 2
    assert all(r["solvable"] and r["leaf"] is None for r in fine["tasks"])

    point = world["tasks"][0]["checks"]["checks"][0]["parameters"]
    edited = {**world, "obstacles": [*world["obstacles"], {
        "id": "o99", "name": "new tower", "type": "circle", "radius": 12.0, "height": 0,
        "position": {"x": point["x"], "y": point["y"], "z": 0.0}}]}
    after = (await client.post("/api/editor/tasks/recheck", json={"session": edited})).json()
    assert after["solvable"] == 1 and after["total"] == 2
    first, second = after["tasks"]
    assert not first["solvable"] and second["solvable"]
    assert first["leaf"] == "checks[0]" and first["endpoint"] == "drone_has_visited_position"
    assert "inside obstacle o99" in first["reason"]

    drone = world["tasks"][1]["checks"]["checks"][0]["parameters"]["drone_id"]
    gone = {**world, "drones": [d for d in world["drones"] if d["id"] != drone]}
    missing = (await client.post("/api/editor/tasks/recheck", json={"session": gone})).json()
    assert not missing["tasks"][1]["solvable"] and drone in missing["tasks"][1]["reason"]

    low = {**world, "drones": [{**d, "max_altitude": 12} for d in world["drones"]]}
    ceiling = (await client.post("/api/editor/tasks/recheck", json={"session": low})).json()
    assert all(not r["solvable"] and r["leaf"] == "checks[0]" and "above" in r["reason"]
               and "12 m" in r["reason"] for r in ceiling["tasks"])

    outside = {**world, "map_size_m": [50.0, 50.0],
               "drones": [{**d, "position": {"x": 5.0 + 3 * k, "y": 5.0, "z": 0.0}}
                          for k, d in enumerate(world["drones"])],
               "targets": [], "obstacles": []}
    off_map = (await client.post("/api/editor/tasks/recheck", json={"session": outside})).json()
    assert all("outside the 50 x 50 m map" in r["reason"] for r in off_map["tasks"])


async def test_a_task_is_proved_by_the_oracle_on_a_sandbox_swarm(
        console: tuple[httpx.AsyncClient, Path]) -> None:
    client, folder = console
    world = _world()
    world["tasks"] = [d["task"] for d in (await _drawn(client, world, count=2))["tasks"]]
    started = await client.post("/api/editor/proofs", json={"session": world, "task_id": "t01"})
    assert started.status_code == 202, started.text
    proof = started.json()
    assert proof["status"] == "running" and proof["task"] == "t01"
    busy = await client.post("/api/editor/proofs", json={"session": world, "task_id": "t02"})
    assert busy.status_code == 409 and proof["id"] in busy.json()["detail"]
    seen_live = False
    for _ in range(600):
        info = (await client.get("/api/info")).json()
        seen_live = seen_live or any(live["id"] == proof["live"] for live in info["live"])
        proof = (await client.get(f"/api/editor/proofs/{proof['id']}")).json()
        if proof["status"] != "running":
            break
        await asyncio.sleep(0.1)
    record = proof["record"]
    assert proof["status"] == "passed", (proof["error"], record and record["checks"])
    assert proof["tries"] in (1, 2)
    assert record["passed"] and record["checks_passed"] == record["checks_total"] == 2
    assert record["tool_calls"] > 0
    assert [c["path"] for c in record["checks"]] == ["checks[0]", "checks[1]"]
    assert record["replay"]["paths"] and record["replay"]["t1_s"] > record["replay"]["t0_s"]
    assert seen_live
    info = (await client.get("/api/info")).json()
    assert all(live["id"] != proof["live"] for live in info["live"])
    assert list(folder.iterdir()) == []  # a proof writes nothing

    unknown = await client.post("/api/editor/proofs", json={"session": world, "task_id": "t9"})
    assert unknown.status_code == 422 and "no task 't9'" in unknown.json()["error"]
    missing = await client.get("/api/editor/proofs/proof-99")
    assert missing.status_code == 404


async def test_a_task_the_oracle_cannot_pass_is_proved_failed_naming_the_leaf(
        console: tuple[httpx.AsyncClient, Path]) -> None:
    client, _ = console
    world = _world()
    world["tasks"] = [{"id": "t01", "text": "Photograph the sky.", "checks": {
        "logic": "and", "checks": [{"endpoint": "drone_has_taken_photo",
                                    "parameters": {"drone_id": "d1", "min_count": 1}},
                                   {"endpoint": "drone_has_taken_photo", "expect": False,
                                    "parameters": {"drone_id": "d1", "min_count": 1}}]},
        "budget": {"tool_calls": 20, "sim_time_s": 120}}]
    started = await client.post("/api/editor/proofs", json={"session": world, "task_id": "t01"})
    assert started.status_code == 202
    proof = started.json()
    while proof["status"] == "running":
        await asyncio.sleep(0.1)
        proof = (await client.get(f"/api/editor/proofs/{proof['id']}")).json()
    assert proof["status"] == "failed" and proof["tries"] == 2  # the oracle's two flights
    assert not proof["record"]["passed"], proof
    verdicts = {c["path"]: c["passed"] for c in proof["record"]["checks"]}
    assert verdicts == {"checks[0]": True, "checks[1]": False}


async def test_templates_are_saved_into_the_save_folder(
        console: tuple[httpx.AsyncClient, Path]) -> None:
    client, folder = console
    builtin = await client.post("/api/editor/templates/save", json={"text": PHOTO})
    assert builtin.status_code == 422 and builtin.json()["field"] == "id"
    assert "built-in" in builtin.json()["error"]
    mine = PHOTO.replace('"id": "photo_at_point"', '"id": "my_photo"')
    saved = await client.post("/api/editor/templates/save", json={"text": mine})
    assert saved.status_code == 200, saved.text
    path = folder / "templates" / "my_photo.json"
    assert saved.json()["path"] == str(path)
    assert json.loads(path.read_text())["id"] == "my_photo"
    listed = (await client.get("/api/editor/templates")).json()["templates"]
    assert {"id": "my_photo", "source": "saved"}.items() <= listed[-1].items()
    read = (await client.get("/api/editor/templates/my_photo")).json()
    assert read["source"] == "saved" and json.loads(read["text"])["id"] == "my_photo"
    (folder / "templates" / "broken.json").write_text("{")
    listed = (await client.get("/api/editor/templates")).json()["templates"]
    assert "not JSON" in next(t for t in listed if t["file"] == "broken.json")["error"]


@pytest.mark.parametrize("family", ["area_search", "area_assignment_and_patrol",
                                    "target_assignment", "target_tracking", "resilience"])
async def test_shipped_tasks_are_rechecked_solvable(console: tuple[httpx.AsyncClient, Path],
                                                    family: str) -> None:
    """No false alarm: every task the shipped suite proved is re-checked solvable."""
    client, _ = console
    session = json.loads((ROOT / f"benchmark/sessions/{family}-hard-2.json").read_text())
    answer = (await client.post("/api/editor/tasks/recheck", json={"session": session})).json()
    assert answer["total"] == len(session["tasks"]) > 0
    assert [r["reason"] for r in answer["tasks"] if not r["solvable"]] == []


@pytest.mark.mavsdk
def test_a_served_console_refuses_agents_the_task_editor(tmp_path: Path) -> None:
    """`mavswarm serve` (agents have keys there): its console's task editor answers an
    operator and refuses an agent with 403, over a real socket to a real server process."""
    (tmp_path / "world.json").write_text(json.dumps(_world()))
    port = unused_tcp_port()
    proc = subprocess.Popen(
        [*MAVSWARM, "serve", "--sessions", "world.json", "--port", str(port),
         "--key", "operator=op", "--key", "agent=ag"],
        cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        read_until(proc, "web console:", 60)
        base = f"http://127.0.0.1:{port}/console"
        with httpx.Client(base_url=base, timeout=60) as client:
            for key, status in (("op", 200), ("ag", 403)):
                listed = client.get("/api/editor/templates", headers={"X-API-Key": key})
                assert listed.status_code == status, listed.text
                drawn = client.post("/api/editor/templates/instantiate",
                                    headers={"X-API-Key": key},
                                    json={"session": _world(), "text": PHOTO})
                assert drawn.status_code == status, drawn.text
                if status == 403:
                    assert "checks" not in drawn.text and "agent" in drawn.json()["detail"]
    finally:
        proc.terminate()
        try:
            proc.wait(15)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)
