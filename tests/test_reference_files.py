"""MultiUAV-Plat session files load and fly: the values our physics reads differently (battery
capacity as a size label, homes in the air, moving targets) are mapped in one place with a
note, and a session that cannot start or load still records each of its tasks as failed."""

from __future__ import annotations

import json
import signal
from pathlib import Path
from typing import Any

import pytest

from benchmark.authoring.importer import import_session_file
from benchmark.running.orchestrator import RunPlan, run_benchmark
from benchmark.running.results import read_records
from benchmark.server.serve import serve_rest
from emulator.clock import ClockConfig
from emulator.scenario import load_scenario, scenario_from_dict
from emulator.swarm import PortPlan, Swarm
from tests.bench_fixtures import overcrowded, reference_session, small_session, write_json
from tests.cli_fixtures import ROOT, read_until, start_up
from tests.ports import unused_udp_port
from tests.rest_fixtures import as_role, served

SHARED_SESSIONS = ROOT.parent / "shared" / "sessions"
EXAMPLES = sorted(SHARED_SESSIONS.glob("*.json")) if SHARED_SESSIONS.is_dir() else []


def _airborne_reference() -> dict[str, Any]:
    data = reference_session()
    first, second = data["drones"][:2]
    first["battery_capacity"] = 74
    first["position"]["z"] = 9.0  # spawned in the air: home defaults to the same point
    second["battery_capacity"] = 250_000
    data["targets"].append({"id": "77aa88bb", "name": "Moving Target 1", "type": "moving",
                            "position": {"x": 500.0, "y": 500.0, "z": 0.0}, "radius": 5,
                            "velocity": {"x": 1.0, "y": 0.0, "z": 0.0}})
    return data


def test_reference_values_are_mapped_with_a_note() -> None:
    scenario = scenario_from_dict(_airborne_reference(), source="ref.json")
    first, second, third = scenario.vehicles[:3]
    assert first.battery_capacity_mah == 7400.0 and first.battery_pct == 100.0
    assert first.position_m[2] == 9.0 and first.home_m == (first.position_m[0],
                                                           first.position_m[1], 0.0)
    assert second.battery_capacity_mah == 100_000.0
    assert third.battery_capacity_mah == 8000.0  # the fixture's label 80
    notes = "\n".join(scenario.notes)
    assert "battery_capacity 74 is a MultiUAV-Plat size label; flown as 7400 mAh" in notes
    assert "battery_capacity 250000 mAh is above 100000" in notes
    assert "home_position.z 9 m" in notes
    assert "77aa88bb" not in notes  # a moving target clear of obstacles moves as there
    assert scenario.world.target("77aa88bb").motion.mode == "velocity"
    ours = scenario_from_dict(small_session([]), source="ours.json")
    assert not ours.notes


async def _flies(path: Path) -> None:
    scenario = load_scenario(path)
    ports = PortPlan(bind_host="127.0.0.1", bind_port=0, api_port=unused_udp_port(), gcs_port=0)
    async with Swarm(scenario, clock=ClockConfig(stepped=True), ports=ports) as swarm:
        assert swarm.n == len(scenario.vehicles)
        for ap, spec in zip(swarm.fleet.autopilots, scenario.vehicles, strict=True):
            assert ap.params["BAT_CAPACITY"] == spec.battery_capacity_mah
            assert ap.home_m[2] == 0.0
            assert ap.in_air == (spec.position_m[2] > 0.0)


@pytest.mark.skipif(not EXAMPLES, reason="needs the reference example files in ../shared")
@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
async def test_the_reference_example_files_start_a_swarm(path: Path) -> None:
    await _flies(path)


@pytest.mark.slow
def test_up_starts_a_reference_file_and_says_what_it_mapped(tmp_path: Path) -> None:
    path = write_json(tmp_path / "ref.json", _airborne_reference())
    proc = start_up("--session", str(path), "--stepped", "--bind-host", "127.0.0.1",
                    "--bind-port", str(unused_udp_port()), "--api-port",
                    str(unused_udp_port()), "--gcs-port", "0", "--no-truth")
    try:
        text = read_until(proc, "MAVProxy")
    finally:
        proc.send_signal(signal.SIGINT)
        proc.communicate(timeout=20)
    assert "note: drones[0] (id a1b1c1d1).battery_capacity 74" in text
    assert "4 vehicles from" in text
    assert proc.returncode == 0


@pytest.mark.mavsdk
def test_an_imported_reference_file_runs_and_records_every_task(tmp_path: Path) -> None:
    data = _airborne_reference()
    drone = data["drones"][2]["id"]
    data["tasks"] = [{"id": "a1b2c3d4", "name": "Take off", "content": "Take off.",
                      "execution_check_apis": {"logic": "and", "checks": [
                          {"endpoint": "/check/drone_has_taken_off",
                           "parameters": {"drone_id": drone}}]}}]
    source = write_json(tmp_path / "ref.json", data)
    taken: set[str] = set()
    path, notes = import_session_file(source, tmp_path / "in", taken=taken)
    twin, twin_notes = import_session_file(source, tmp_path / "in", taken=taken)
    assert path != twin and path.exists() and twin.exists()
    assert any("was taken by an earlier file" in n for n in twin_notes)
    assert any("size label" in n for n in notes)
    plan = RunPlan(sessions=(path,), agent="noop", out_dir=tmp_path / "out")
    outcome = run_benchmark(plan, progress=lambda _: None)
    assert outcome.errors == []
    (record,) = read_records(plan.results_path)
    assert record["task"] == "a1b2c3d4" and record["finish"] == "finished"
    assert record["passed"] is False  # noop never takes off


@pytest.mark.mavsdk
def test_sessions_that_cannot_start_or_load_record_each_task(tmp_path: Path) -> None:
    unflyable = overcrowded(small_session(["takeoff_hold", "checkpoint"]))
    unflyable["id"] = "unflyable"
    unloadable = small_session(["takeoff_hold"])
    unloadable["id"] = "unloadable"
    unloadable["drones"][0]["position"]["z"] = -5.0
    paths = (write_json(tmp_path / "a.json", unflyable),
             write_json(tmp_path / "b.json", unloadable))
    plan = RunPlan(sessions=paths, agent="noop", out_dir=tmp_path / "out")
    outcome = run_benchmark(plan, progress=lambda _: None)
    assert outcome.errors == []
    records = read_records(plan.results_path)
    by_session: dict[str, list[dict[str, Any]]] = {}
    for record in records:
        by_session.setdefault(record["session"], []).append(record)
    assert [r["task"] for r in by_session["unflyable"]] == ["t01", "t02"]
    assert [r["task"] for r in by_session["unloadable"]] == ["t01"]
    for record in records:
        assert record["finish"] == "task_error" and record["passed"] is False
    assert "cannot start" in by_session["unflyable"][0]["error"]
    assert "1 to 250 vehicles" in by_session["unflyable"][0]["error"]
    assert "cannot be loaded" in by_session["unloadable"][0]["error"]
    assert json.loads(json.dumps(records)) == records
    again = run_benchmark(plan, progress=lambda _: None)  # resumed: nothing left to record
    assert again.records_written == 0 and len(read_records(plan.results_path)) == 3


REFERENCE_DRONE_FIELDS = {
    "id", "name", "model", "status", "position", "heading", "speed", "perceived_radius",
    "task_radius", "battery_level", "battery_capacity", "max_speed", "max_altitude",
    "home_position", "created_at", "last_updated"}


@pytest.mark.mavsdk
async def test_compat_drones_have_every_reference_field() -> None:
    async with served() as s:
        headers = as_role("agent")
        drones = (await s.client.get("/drones", headers=headers)).json()
        first = s.data["drones"][0]
        assert {d["id"] for d in drones} == {d["id"] for d in s.data["drones"]}
        for drone in drones:
            assert set(drone) == REFERENCE_DRONE_FIELDS, set(drone) ^ REFERENCE_DRONE_FIELDS
            assert set(drone["position"]) == set(drone["home_position"]) == {"x", "y", "z"}
        by_name = {d["name"]: d["id"] for d in drones}  # a client resolves names to ids
        assert by_name[first["name"]] == first["id"]
        one = (await s.client.get(f"/drones/{first['id']}", headers=headers)).json()
        assert one["battery_capacity"] == first["battery_capacity"]
        assert one["max_altitude"] == first["max_altitude"] and one["status"] == "idle"


@pytest.mark.mavsdk
async def test_requests_without_a_key_act_as_the_agent_only_when_open() -> None:
    async with served() as s:
        sid = s.live.id
        assert (await s.client.get("/drones")).status_code == 401
        s.hub.open_access = True
        assert (await s.client.get("/drones")).status_code == 200
        took = await s.client.post(f"/drones/{s.data['drones'][0]['id']}/command/take_off",
                                   params={"altitude": 5})
        assert took.status_code == 200 and took.json()["status"] == "success", took.text
        assert (await s.client.get(f"/check/sessions/{sid}/task")).status_code == 403
        assert (await s.client.get("/sessions")).status_code == 403
        wrong = await s.client.get("/drones", headers={"X-API-Key": "wrong"})
        assert wrong.status_code == 401  # a key that is sent must be valid


async def test_open_access_needs_exactly_one_session(tmp_path: Path) -> None:
    paths = [write_json(tmp_path / f"{k}.json", small_session([])) for k in "ab"]
    with pytest.raises(ValueError, match="exactly one session"):
        await serve_rest(paths, port=0, open_access=True)


@pytest.mark.mavsdk
async def test_compat_nearby_gives_full_records_of_what_is_perceived_only() -> None:
    data = small_session(["takeoff_hold"])
    target = data["targets"][0]
    near_target = {"x": target["position"]["x"], "y": target["position"]["y"] + 45.0, "z": 0.0}
    data["drones"][0]["position"] = near_target  # inside its sensor's reach of the target
    data["drones"][0].pop("home_position", None)
    async with served(data=data) as s:
        headers = as_role("agent")
        files = {kind: {e["id"]: e for e in s.data[kind]} for kind in ("targets", "obstacles")}
        seen_any = False
        for drone in s.data["drones"]:
            near = (await s.client.get(f"/drones/{drone['id']}/nearby", headers=headers)).json()
            truth = s.live.gateway.nearby(drone["id"]).data or {}
            for kind in ("drones", "targets", "obstacles"):
                assert {e["id"] for e in near[kind]} == {e["id"] for e in truth.get(kind, [])}
            for entity in near["drones"]:
                assert set(entity) == REFERENCE_DRONE_FIELDS and entity["id"] != drone["id"]
            for kind in ("targets", "obstacles"):
                for entity in near[kind]:
                    raw = files[kind][entity["id"]]  # name, type, geometry as in the file
                    assert {k: entity[k] for k in raw} == raw
                    by_id = await s.client.get(f"/{kind}/{entity['id']}", headers=headers)
                    assert by_id.json() == entity
                    seen_any = True
        assert seen_any, "the first drone perceives the first target"


@pytest.mark.mavsdk
async def test_compat_move_along_path_reports_the_points_reached() -> None:
    async with served() as s:
        headers = as_role("agent")
        first, second = s.data["drones"][:2]
        x, y = first["position"]["x"], first["position"]["y"]
        path = [{"x": x + 8.0, "y": y, "z": 6.0}, {"x": x + 8.0, "y": y - 8.0, "z": 6.0}]
        grounded = await s.client.post(f"/drones/{second['id']}/command/move_along_path",
                                       headers=headers, json=path)
        assert grounded.json()["status"] == "error"
        assert grounded.json()["successful_points"] is None
        assert grounded.json()["unsuccessful_points_count"] is None
        took = await s.client.post(f"/drones/{first['id']}/command/take_off", headers=headers,
                                   params={"altitude": 6})
        assert took.json()["status"] == "success", took.text
        flown = (await s.client.post(f"/drones/{first['id']}/command/move_along_path",
                                     headers=headers, json=path)).json()
        assert flown["status"] == "success", flown
        assert flown["successful_points_count"] == 2 and flown["unsuccessful_points"] == []
        assert flown["successful_points"] == [[p["x"], p["y"], p["z"]] for p in path]


@pytest.mark.mavsdk
async def test_compat_current_session_has_the_reference_metadata() -> None:
    async with served() as s:
        current = (await s.client.get("/sessions/current", headers=as_role("agent"))).json()
        for field in ("id", "name", "description", "status", "task_type", "task_description",
                      "canvas_width", "canvas_height", "created_at", "last_updated"):
            assert field in current, field
        assert current["status"] == "active"
        assert current["task_description"] == s.data["tasks"][0]["text"]
        assert [current["canvas_width"], current["canvas_height"]] == s.data["map_size_m"]
        assert "targets" not in current and "obstacles" not in current
        assert "statistics" not in current and "checks" not in str(current)
        assert current["description"] == ""  # ours counts the map's targets and obstacles
        staff = (await s.client.get("/sessions/current", headers=as_role("operator"))).json()
        assert staff["description"] == s.data["description"]


@pytest.mark.mavsdk
async def test_reference_check_endpoints_for_admins_only() -> None:
    async with served() as s:
        drone = s.data["drones"][0]["id"]
        url = "/check/drone_has_taken_off"
        params = {"drone_id": drone, "min_altitude": "3.0"}
        before = await s.client.get(url, params=params, headers=as_role("admin"))
        assert before.status_code == 200 and before.json()["result"] is False, before.text
        for role in ("agent", "operator"):
            denied = await s.client.get(url, params=params, headers=as_role(role))
            assert denied.status_code == 403
        took = await s.client.post(f"/drones/{drone}/command/take_off", params={"altitude": 6},
                                   headers=as_role("agent"))
        assert took.json()["status"] == "success"
        after = (await s.client.get(url, params=params, headers=as_role("admin"))).json()
        assert after["result"] is True and after["parameters"]["min_altitude"] == 3.0, after
        height = (await s.client.get("/check/drone_altitude", headers=as_role("admin"),
                                     params={"drone_id": drone, "expected_altitude": "6",
                                             "tolerance": "0.5"})).json()
        assert height.get("result") is True, height
        assert height["value"] == pytest.approx(6.0, abs=0.5)
        unknown = await s.client.get("/check/drone_is_happy", headers=as_role("admin"))
        assert unknown.status_code == 404
        bad = await s.client.get(url, params={"drone_id": "zz"}, headers=as_role("admin"))
        assert bad.status_code == 422 and "zz" in bad.json()["detail"]
