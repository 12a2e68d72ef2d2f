"""The scenario editor in headless Chromium: an invalid edit (a drone inside an obstacle) is
shown and refused; a session edited (obstacle placed, drone dragged, task text and budget
changed) and saved loads in `mavswarm up` and runs in `mavswarm bench run`; a generated level
to start from is picked among the benchmark's five families, as the server lists them."""

from __future__ import annotations

import json
import os
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from benchmark.authoring.scenarios import FAMILIES, LEVELS
from benchmark.authoring.session_file import load_session
from tests.browser_fixtures import (
    map_view,
    open_page,
    screen_of,
    shot,
)
from tests.cli_fixtures import MAVSWARM, ROOT, read_until, run_in_process_thread, start_up
from tests.ports import unused_tcp_port, unused_udp_port

pytestmark = [pytest.mark.browser]


@pytest.fixture(scope="module")
def editor(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, Path]]:
    """`mavswarm replay` serving the editor, shared by the module's tests (one saves under
    its folder, the other only loads generated levels), and a session file to start from."""
    tmp_path = tmp_path_factory.mktemp("editor")
    source = json.loads((ROOT / "benchmark/sessions/area_search-easy-1.json").read_text())
    source["tasks"], source["id"] = source["tasks"][:1], "edited-1"
    (tmp_path / "start.json").write_text(json.dumps(source))
    results = tmp_path / "results"
    results.mkdir()
    (results / "results.jsonl").write_text("")
    port = unused_tcp_port()
    proc = subprocess.Popen([*MAVSWARM, "replay", str(results), "--port", str(port)],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        read_until(proc, "http://", 30)
        yield f"http://127.0.0.1:{port}", tmp_path
    finally:
        proc.terminate()
        proc.wait(10)


def _click_world(page: Any, x_m: float, y_m: float) -> None:
    box = page.locator("#map2d").bounding_box()
    sx, sy = screen_of(map_view(page), x_m, y_m)
    page.mouse.click(box["x"] + sx, box["y"] + sy)


def _status(page: Any, text: str) -> str:
    page.wait_for_function(f"(document.getElementById('editor-status').textContent || '')"
                           f".includes({json.dumps(text)})", timeout=15_000)
    return page.text_content("#editor-status") or ""


def test_an_edited_session_is_validated_saved_and_loads(browser: Any,
                                                       editor: tuple[str, Path]) -> None:
    url, folder = editor
    with open_page(browser, f"{url}/editor") as page:
        _status(page, "valid: 1 drones")  # the blank map
        page.select_option("#start-source", "file")
        page.fill("#start-path", str(folder / "start.json"))
        page.click("#start-load")
        _status(page, "valid: 3 drones, 3 targets, 6 obstacles, 1 tasks")

        page.select_option("#editor-tool", "add obstacle circle")
        _click_world(page, 520.0, 80.0)
        _status(page, "7 obstacles")
        page.select_option("#editor-tool", "add drone")
        _click_world(page, 520.0, 80.0)
        refused = _status(page, "invalid")
        assert "drones[3]" in refused and "inside obstacle" in refused
        page.click("#save")
        assert "not saved" in _status(page, "not saved")
        assert not (folder / "sessions").exists()
        shot(page, "editor-refused")
        page.click("#delete-selected")
        _status(page, "valid: 3 drones")

        page.select_option("#editor-tool", "select")
        d1 = page.evaluate("window.consoleView.state.session.drones[0].position")
        box = page.locator("#map2d").bounding_box()
        view = map_view(page)
        sx, sy = screen_of(view, d1["x"], d1["y"])
        tx, ty = screen_of(view, d1["x"] + 60.0, d1["y"] - 40.0)
        page.mouse.move(box["x"] + sx, box["y"] + sy)
        page.mouse.down()
        page.mouse.move(box["x"] + (sx + tx) / 2, box["y"] + (sy + ty) / 2, steps=4)
        page.mouse.move(box["x"] + tx, box["y"] + ty, steps=4)
        page.mouse.up()
        moved = page.evaluate("window.consoleView.state.session.drones[0].position")
        assert moved["x"] == pytest.approx(d1["x"] + 60.0, abs=2.0)
        assert moved["y"] == pytest.approx(d1["y"] - 40.0, abs=2.0)

        page.fill("#task-text-0", "Fly Drone 2 somewhere nice and take a photo.")
        page.dispatch_event("#task-text-0", "change")
        page.fill("#task-calls-0", "30")
        page.dispatch_event("#task-calls-0", "change")
        page.fill("#save-path", "sessions/edited.json")
        page.click("#save")
        saved = _status(page, "saved to")
        shot(page, "editor-saved")
    path = folder / "sessions" / "edited.json"
    assert str(path) in saved
    session = load_session(path)
    assert session.tasks[0].text == "Fly Drone 2 somewhere nice and take a photo."
    assert session.tasks[0].budget is not None and session.tasks[0].budget.tool_calls == 30
    assert len(session.scenario.world.obstacles) == 7
    assert session.scenario.vehicles[0].position_m[0] == pytest.approx(moved["x"])

    up = start_up("--session", str(path), "--no-truth", "--api-port", str(unused_udp_port()),
                  "--gcs-port", "0", "--bind-port", str(unused_udp_port()))
    try:
        assert "3 vehicles from" in read_until(up, "vehicles from", 30)
    finally:
        up.terminate()
        up.wait(10)
    run = run_in_process_thread("bench", "run", "--agent", "noop", "--sessions", str(path),
                                "--out", str(folder / "run"), cwd=folder)
    assert run.returncode == 0, run.stdout + run.stderr
    records = (folder / "run" / "results.jsonl").read_text().splitlines()
    assert len(records) == 1 and json.loads(records[0])["session"] == "edited-1"


def test_a_generated_level_is_picked_among_every_family(browser: Any,
                                                       editor: tuple[str, Path]) -> None:
    url, _ = editor
    with open_page(browser, f"{url}/editor") as page:
        _status(page, "valid: 1 drones")
        options = page.eval_on_selector_all("#start-family option", "els => els.map(e => e.value)")
        assert options == list(FAMILIES) and len(options) == 5
        levels = page.eval_on_selector_all("#start-level option", "els => els.map(e => e.value)")
        assert levels == list(LEVELS)
        assert page.get_attribute("#start-index", "max") == "5"
        for family in ("target_tracking", "resilience"):  # the two the page used to miss
            page.select_option("#start-source", "level")
            page.select_option("#start-family", family)
            page.select_option("#start-level", "easy")
            page.evaluate("document.getElementById('editor-status').textContent = ''")
            page.click("#start-load")
            page.wait_for_function(
                f"window.consoleView.state.session.family === {json.dumps(family)}",
                timeout=15_000)
            drones = page.evaluate("window.consoleView.state.session.drones.length")
            assert drones >= 2 and "0 tasks" in _status(page, f"valid: {drones} drones")
