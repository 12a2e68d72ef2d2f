"""What the console reads and writes, without a browser: thinned replay paths stay within
their tolerance of the truth, a truth file carries its scenario, results without replay data
open with a note, the editor refuses invalid sessions naming the entity, console keys, and
the inspector's route and default port that report.html links to."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient

from benchmark.running.replay_data import (
    TOLERANCE_M,
    decode_paths,
    encode_window,
    read_json_gz,
    thin_rows,
    write_json_gz,
)
from console.app import ConsoleState, create_console_app
from console.auth import ConsoleAuth
from console.editor import EditorError, blank_session, save_session, validate_session
from console.results_index import NO_REPLAY_NOTE, open_paths
from emulator.scenario import default_scenario, scenario_from_dict
from emulator.scenario_export import scenario_to_dict
from emulator.truth import TruthLog, TruthRecorder
from mavswarm.cli import build_parser
from tests.cli_fixtures import ROOT


def _flight(dt: float = 0.02) -> np.ndarray:
    """A climb, an accelerating leg, a cruise, a braking stop, a turn and a curved leg."""
    t = np.arange(0.0, 120.0, dt)
    x = np.where(t < 10, 0.0, np.where(t < 70, 0.5 * np.clip(t - 10, 0, 8) ** 2
                                       + 8.0 * np.clip(t - 18, 0, None), 0.0))
    x = np.where(t >= 70, 32 + 8.0 * 52 + 30 * np.sin((t - 70) / 10), x)
    y = np.where(t >= 70, 40 * (1 - np.cos((t - 70) / 10)), 0.0)
    z = np.clip(t, 0, 10) * 2.0
    yaw = (t * 7.0) % 360.0
    battery = 100.0 - t * 0.05
    return np.column_stack([t, x, y, z, yaw, battery])


def test_thinned_paths_stay_within_tolerance_of_the_truth() -> None:
    rows = _flight()
    kept = thin_rows(rows)
    assert kept.shape[0] < rows.shape[0] / 10
    assert kept[0, 0] == rows[0, 0] and kept[-1, 0] == rows[-1, 0]
    for c in (1, 2, 3):
        error = np.abs(np.interp(rows[:, 0], kept[:, 0], kept[:, c]) - rows[:, c])
        assert error.max() <= 8 * TOLERANCE_M, (c, error.max())


def test_a_window_round_trips_through_the_stored_form(tmp_path: Path) -> None:
    recorder = TruthRecorder(["d1", "d2"])
    rows = _flight()
    for r in rows:
        position = np.array([[r[1], r[2], r[3]], [-r[1], r[2], 0.0]])
        recorder.record_step(r[0], position, np.array([r[4], 0.0]), np.array([r[5], 90.0]),
                             np.array([True, True]))
    recorder.record_event(30.0, "d1", "photo", index=1, position_m=[1.0, 2.0, 3.0])
    data = encode_window(recorder, 20.0, 90.0, [{"i": 0, "name": "hover"}])
    path = write_json_gz(tmp_path / "r.json.gz", data)
    loaded = read_json_gz(path)
    assert loaded["t0_s"] == 20.0 and loaded["t1_s"] == 90.0
    assert loaded["events"] == [[30.0, "d1", "photo", {"index": 1,
                                                      "position_m": [1.0, 2.0, 3.0]}]]
    assert loaded["calls"] == [{"i": 0, "name": "hover"}]
    paths = decode_paths(loaded["paths"], loaded["t0_s"])
    for drone in ("d1", "d2"):
        got = paths[drone]
        assert got[0, 0] == pytest.approx(20.0) and got[-1, 0] == pytest.approx(90.0)
        for t in np.linspace(20.0, 90.0, 57):
            truth = recorder.position_at(drone, t)
            x, y = (np.interp(t, got[:, 0], got[:, c]) for c in (1, 2))
            assert math.dist((x, y), truth[:2]) < 1.0, (drone, t)
    assert path.stat().st_size < 4000


def test_a_truth_file_carries_its_scenario(tmp_path: Path) -> None:
    scenario = default_scenario(4)
    recorder = TruthRecorder([v.id for v in scenario.vehicles])
    recorder.record_step(0.0, np.zeros((4, 3)), np.zeros(4), np.full(4, 100.0),
                         np.zeros(4, dtype=bool))
    path = recorder.export(tmp_path / "x.truth.npz",
                           attachments={"scenario": json.dumps(scenario_to_dict(scenario))})
    assert TruthLog.load(path).vehicle_ids == ("d1", "d2", "d3", "d4")
    text = TruthLog.attachment(path, "scenario")
    assert text is not None
    again = scenario_from_dict(json.loads(text))
    for a, b in zip(scenario.world.obstacles, again.world.obstacles, strict=True):
        assert (a.kind, a.height_m) == (b.kind, b.height_m)
        assert a.footprint.area == pytest.approx(b.footprint.area, rel=1e-3)
    assert [t.kind for t in again.world.targets] == [t.kind for t in scenario.world.targets]
    assert again.vehicles == scenario.vehicles
    assert TruthLog.attachment(recorder.export(tmp_path / "bare.npz"), "scenario") is None


def test_results_without_replay_data_open_with_a_note(tmp_path: Path) -> None:
    record = {"key": "s/t01/noop/0", "session": "s", "task": "t01", "agent": "noop",
              "trial": 0, "passed": False, "checks": []}
    (tmp_path / "old").mkdir()
    (tmp_path / "old" / "results.jsonl").write_text(json.dumps(record) + "\n")
    index = open_paths([tmp_path])
    run = index.runs["old"]
    assert run.rows()[0]["has_replay"] is False
    view = run.task_view(run.records[0])
    assert view["note"] == NO_REPLAY_NOTE and view["replay"] is None
    with pytest.raises(ValueError, match="neither a results folder nor a"):
        open_paths([tmp_path / "old" / "missing"])
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match=r"no results\.jsonl in it"):
        open_paths([tmp_path / "empty"])


def test_the_editor_refuses_invalid_sessions_naming_the_entity(tmp_path: Path) -> None:
    session = json.loads((ROOT / "benchmark/sessions/area_search-easy-1.json").read_text())
    assert validate_session(session)["tasks"] == 20
    obstacle = session["obstacles"][0]
    inside = json.loads(json.dumps(session))
    inside["drones"][1]["position"] = dict(obstacle["position"], z=0.0)
    with pytest.raises(EditorError, match="inside obstacle") as refused:
        validate_session(inside)
    assert refused.value.entity == ("drones", 1)
    overlap = json.loads(json.dumps(session))
    overlap["drones"][2]["position"] = dict(overlap["drones"][0]["position"])
    with pytest.raises(EditorError, match="overlaps") as refused:
        validate_session(overlap)
    assert refused.value.entity == ("drones", 2)
    budget = json.loads(json.dumps(session))
    budget["tasks"][3]["budget"]["tool_calls"] = 0
    with pytest.raises(EditorError) as refused:
        validate_session(budget)
    assert refused.value.entity == ("tasks", 3)
    with pytest.raises(EditorError, match="saved under"):
        save_session(blank_session(), Path("../outside.json"), tmp_path)
    with pytest.raises(EditorError, match=r"ends in \.json"):
        save_session(blank_session(), Path("x.txt"), tmp_path)
    with pytest.raises(EditorError):
        save_session(inside, Path("bad.json"), tmp_path)
    assert not (tmp_path / "bad.json").exists()
    saved = save_session(blank_session(), Path("ok/blank.json"), tmp_path)
    assert Path(saved["path"]) == tmp_path / "ok" / "blank.json"


def test_console_keys() -> None:
    auth, key = ConsoleAuth.single_key()
    assert auth.check(key).role == "operator"
    assert auth.check(None).status == 401 and auth.check("nope").status == 401
    roles = {"a": "agent", "o": "operator", "x": "admin"}
    hub_auth = ConsoleAuth(roles.get)
    assert hub_auth.check("a").status == 403
    assert hub_auth.check("o").role == "operator" and hub_auth.check("x").role == "admin"


def test_the_inspector_route_and_default_port_report_html_links_to(tmp_path: Path) -> None:
    args = build_parser().parse_args(["replay", str(tmp_path)])
    assert (args.host, args.port) == ("127.0.0.1", 8765)
    up = build_parser().parse_args(["up", "--web"])
    assert up.web and up.web_port == 8765
    state = ConsoleState(ConsoleAuth(lambda _k: None, open_access=True))
    client = TestClient(create_console_app(state))
    page = client.get("/inspect/area_search-easy-1/t03?trial=2")
    assert page.status_code == 200 and "/static/app.js" in page.text
    assert client.get("/static/app.js").status_code == 200
    assert client.get("/static/nothing.js").status_code == 404
    assert client.get("/api/task/s/t?trial=0").status_code == 404
    refused = client.post("/api/editor/validate", content=b"[1, 2]")
    assert refused.status_code == 422 and refused.json()["ok"] is False
