"""The scenario editor as people use it, in headless Chromium: a load that fails (a typo in a
file name, a level that does not exist) leaves the session on the page as it was; edits are
undone and redone (buttons and Ctrl+Z / Ctrl+Y), a load included; the shipped sessions are
listed to open, and an edited copy is proposed a new id and cannot be saved under a shipped
session's id (its results would mix with the shipped session's)."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from benchmark.authoring.scenarios import all_session_keys, session_id
from benchmark.authoring.session_file import load_session
from console.app import ConsoleState
from console.auth import ConsoleAuth
from tests.browser_fixtures import map_view, open_page, screen_of, shot
from tests.cli_fixtures import ROOT
from tests.console_server import serve_console

pytestmark = [pytest.mark.browser]


@pytest.fixture(scope="module")
def editor(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, Path]]:
    root = tmp_path_factory.mktemp("editor")
    state = ConsoleState(ConsoleAuth(lambda _key: None, open_access=True), editor_root=root)
    with serve_console(state) as url:
        yield url, root


def _status(page: Any, text: str) -> str:
    page.wait_for_function(f"(document.getElementById('editor-status').textContent || '')"
                           f".includes({json.dumps(text)})", timeout=15_000)
    return page.text_content("#editor-status") or ""


def _session(page: Any) -> dict[str, Any]:
    return dict(page.evaluate("window.consoleView.state.session"))


def _click_world(page: Any, x_m: float, y_m: float) -> None:
    box = page.locator("#map2d").bounding_box()
    sx, sy = screen_of(map_view(page), x_m, y_m)
    page.mouse.click(box["x"] + sx, box["y"] + sy)


def test_a_failed_load_leaves_the_session_on_the_page(browser: Any,
                                                     editor: tuple[str, Path]) -> None:
    url, _ = editor
    with open_page(browser, f"{url}/editor") as page:
        _status(page, "valid: 1 drones")
        page.select_option("#editor-tool", "add drone")
        _click_world(page, 300.0, 300.0)
        _status(page, "valid: 2 drones")
        before = _session(page)
        page.select_option("#start-source", "file")
        page.fill("#start-path", "sessions/no-such-fiel.json")  # a typo: answered 422
        page.click("#start-load")
        failed = _status(page, "cannot load")
        assert "unchanged" in failed
        assert _session(page) == before
        assert page.get_attribute("#editor-status", "class") == "bad"
        page.select_option("#start-source", "level")
        page.evaluate("document.getElementById('start-index').value = '99'")
        page.click("#start-load")
        _status(page, "cannot load level")
        assert _session(page) == before
        drones = page.evaluate("window.consoleView.map.drones.length")
        assert drones == 2  # the map still shows the edited session
        shot(page, "editor-failed-load")


def test_a_session_file_is_uploaded_and_a_broken_one_changes_nothing(
        browser: Any, editor: tuple[str, Path], tmp_path: Path) -> None:
    url, _ = editor
    source = json.loads((ROOT / "benchmark/sessions/area_search-easy-1.json").read_text())
    good, broken = tmp_path / "mine.json", tmp_path / "broken.json"
    good.write_text(json.dumps({**source, "id": "uploaded-1"}))
    broken.write_text('{"schema": "mavswarm.session/1", "drones": [')
    with open_page(browser, f"{url}/editor") as page:
        _status(page, "valid: 1 drones")
        page.select_option("#start-source", "upload")
        page.set_input_files("#start-upload", str(good))
        page.click("#start-load")
        page.wait_for_function("window.consoleView.state.session.id === 'uploaded-1'")
        _status(page, "valid: 3 drones")
        before = _session(page)
        page.set_input_files("#start-upload", str(broken))
        page.click("#start-load")
        failed = _status(page, "cannot load broken.json")
        assert "JSON" in failed and "unchanged" in failed
        assert _session(page) == before


def test_edits_and_loads_are_undone_and_redone(browser: Any, editor: tuple[str, Path]) -> None:
    url, _ = editor
    with open_page(browser, f"{url}/editor") as page:
        _status(page, "valid: 1 drones")
        assert page.is_disabled("#undo") and page.is_disabled("#redo")
        page.select_option("#editor-tool", "add obstacle circle")
        _click_world(page, 300.0, 300.0)
        _status(page, "1 obstacles")
        page.select_option("#editor-tool", "add drone")
        _click_world(page, 100.0, 500.0)
        _status(page, "valid: 2 drones, 0 targets, 1 obstacles")
        page.click("#undo")
        _status(page, "valid: 1 drones, 0 targets, 1 obstacles")
        page.click("#undo")
        _status(page, "valid: 1 drones, 0 targets, 0 obstacles")
        assert page.is_disabled("#undo")
        page.click("#redo")
        _status(page, "valid: 1 drones, 0 targets, 1 obstacles")
        page.click("#map2d", position={"x": 5, "y": 5})  # the page, not a field, has focus
        page.keyboard.press("Control+y")
        _status(page, "valid: 2 drones, 0 targets, 1 obstacles")
        page.keyboard.press("Control+z")
        _status(page, "valid: 1 drones, 0 targets, 1 obstacles")

        page.select_option("#start-source", "shipped")
        page.select_option("#start-shipped", "area_search-easy-1")
        page.click("#start-load")
        _status(page, "valid: 3 drones")
        page.click("#undo")  # the load itself is undone: the edited blank map is back
        _status(page, "valid: 1 drones, 0 targets, 1 obstacles")
        page.click("#redo")
        _status(page, "valid: 3 drones")
        assert _session(page)["id"] == "area_search-easy-1-edit"


def test_shipped_sessions_are_listed_and_saved_only_under_a_new_id(
        browser: Any, editor: tuple[str, Path]) -> None:
    url, root = editor
    listed = httpx.get(f"{url}/api/editor/shipped").json()["sessions"]
    assert [s["id"] for s in listed] == [session_id(*k) for k in all_session_keys()]
    assert httpx.get(f"{url}/api/editor/shipped/..%2F..%2Fpyproject").status_code == 404
    assert httpx.get(f"{url}/api/editor/shipped/area_search-easy-9").status_code == 404
    with open_page(browser, f"{url}/editor") as page:
        _status(page, "valid: 1 drones")
        options = page.eval_on_selector_all("#start-shipped option", "els => els.map(e => e.value)")
        assert len(options) == 125 and "target_tracking-extreme-5" in options
        page.select_option("#start-source", "shipped")
        page.select_option("#start-shipped", "target_assignment-easy-2")
        page.click("#start-load")
        page.wait_for_function("window.consoleView.state.session.family === 'target_assignment'")
        assert page.input_value("#save-id") == "target_assignment-easy-2-edit"
        assert page.input_value("#save-path") == "sessions/target_assignment-easy-2-edit.json"

        page.fill("#save-id", "target_assignment-easy-2")  # back to the shipped id
        page.dispatch_event("#save-id", "change")
        page.fill("#save-path", "sessions/copy.json")
        page.click("#save")
        refused = _status(page, "not saved")
        assert "shipped session" in refused and "new id" in refused
        assert not (root / "sessions" / "copy.json").exists()

        page.fill("#save-id", "my-assignment")
        page.dispatch_event("#save-id", "change")
        page.click("#save")
        saved = _status(page, "saved to")
        shot(page, "editor-save-as")
    path = root / "sessions" / "copy.json"
    assert str(path) in saved
    copy = load_session(path)
    assert copy.id == "my-assignment" and len(copy.tasks) > 0
