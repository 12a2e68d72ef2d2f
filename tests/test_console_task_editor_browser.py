"""The task and template editor in headless Chromium: a built-in template picked and drawn on
the world being edited (its tasks' drones and points highlighted on the map, check trees
readable), a bad edit of it refused naming the field, the tasks added to the session, one
proved by the oracle (it passes and its flight plays on the map), the world edited so that a
task can no longer be flown (the re-check names the leaf), and the session and an edited
template saved into the editor's save folder; a new template written from the page's skeleton
validates and draws."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from benchmark.authoring.session_file import load_session
from console.app import ConsoleState
from console.auth import ConsoleAuth
from tests.browser_fixtures import map_view, open_page, screen_of, shot
from tests.cli_fixtures import ROOT
from tests.console_server import serve_console

pytestmark = [pytest.mark.browser]

KEY = "editor-key"
CHOSEN_RGB = (123, 44, 191)  # the picked drawn task's highlight (console/web/src/taskeditor.js)


@pytest.fixture
def editor(tmp_path: Path) -> Iterator[tuple[str, Path]]:
    world = json.loads((ROOT / "benchmark/sessions/area_search-easy-1.json").read_text())
    (tmp_path / "world.json").write_text(json.dumps({**world, "id": "my-world", "tasks": []}))
    auth, _ = ConsoleAuth.single_key(KEY)
    with serve_console(ConsoleState(auth, editor_root=tmp_path)) as url:
        yield url, tmp_path


def _text(page: Any, selector: str, text: str, timeout_ms: int = 20_000) -> str:
    page.wait_for_function(
        "([s, t]) => (document.querySelector(s)?.textContent || '').includes(t)",
        arg=[selector, text], timeout=timeout_ms)
    return page.text_content(selector) or ""


def _colour_near(page: Any, x_m: float, y_m: float, rgb: tuple[int, int, int],
                 radius_px: int = 9) -> int:
    sx, sy = screen_of(map_view(page), x_m, y_m)
    return int(page.evaluate(
        """([sx, sy, r, rgb]) => {
            const m = window.consoleView.map;
            m.draw();
            const d = m.dpr, x0 = Math.round((sx - r) * d), y0 = Math.round((sy - r) * d);
            const size = Math.round(2 * r * d);
            const data = m.ctx.getImageData(x0, y0, size, size).data;
            let hits = 0;
            for (let k = 0; k < data.length; k += 4) {
                if (Math.abs(data[k] - rgb[0]) < 20 && Math.abs(data[k + 1] - rgb[1]) < 20
                        && Math.abs(data[k + 2] - rgb[2]) < 20) hits++;
            }
            return hits;
        }""", [sx, sy, radius_px, list(rgb)]))


def _click_world(page: Any, x_m: float, y_m: float) -> None:
    page.evaluate("window.scrollTo(0, 0)")
    box = page.locator("#map2d").bounding_box()
    sx, sy = screen_of(map_view(page), x_m, y_m)
    page.mouse.click(box["x"] + sx, box["y"] + sy)


def test_a_template_is_drawn_proved_rechecked_and_saved(browser: Any,
                                                       editor: tuple[str, Path]) -> None:
    url, folder = editor
    with open_page(browser, f"{url}/editor?key={KEY}") as page:
        page.select_option("#start-source", "file")
        page.fill("#start-path", str(folder / "world.json"))
        page.click("#start-load")
        _text(page, "#editor-status", "valid: 3 drones, 3 targets, 6 obstacles, 0 tasks")

        page.wait_for_selector("#template-pick option[value='photo_at_point']", state="attached")
        page.select_option("#template-pick", "photo_at_point")
        page.click("#template-load")
        _text(page, "#template-status", "opened photo_at_point (built-in)")
        original = page.input_value("#template-text")
        page.fill("#template-text", original.replace('"max": 30', '"max": 3'))
        page.click("#template-validate")
        assert "values[0]" in _text(page, "#template-status", "invalid template")
        page.fill("#template-text", original)
        page.click("#template-validate")
        _text(page, "#template-status", "valid template photo_at_point")

        page.fill("#template-count", "2")
        page.click("#template-draw")
        _text(page, "#template-status", "drew 2 tasks of photo_at_point")
        drawn = page.evaluate("window.consoleView.tasks.drawn")
        assert len(drawn) == 2
        tree = page.text_content("#drawn-tree-0") or ""
        assert "AND" in tree and "drone has visited position" in tree
        assert "drone has taken photo" in tree
        assert page.text_content("#drawn-check-0") == "solvable"
        first = drawn[0]["entities"]
        entities = page.text_content("#drawn-entities-0") or ""
        assert f"drones: {first['drones'][0]}" in entities
        x, y = first["points"][0]
        assert _colour_near(page, x, y, CHOSEN_RGB) > 10  # the chosen task's point
        drone = page.evaluate(f"window.consoleView.state.session.drones.find("
                              f"d => d.id === {json.dumps(first['drones'][0])}).position")
        assert _colour_near(page, drone["x"], drone["y"], CHOSEN_RGB, 16) > 10
        shot(page, "task-editor-drawn")

        page.click("#drawn-add")
        _text(page, "#editor-status", "2 tasks")
        _text(page, "#recheck-status", "re-check: 2 of 2 tasks solvable")
        assert _colour_near(page, x, y, CHOSEN_RGB) == 0  # added: no longer a draft
        start = page.evaluate("window.consoleView.map.drones.map(d => [d.x, d.y])")

        page.click("#task-prove-0")
        status = _text(page, "#proof-status", "t01 passed", 90_000)
        assert "2/2 checks" in status and "flight " in status
        leaves = page.eval_on_selector_all("#proof li.leaf", "els => els.map(e => e.className)")
        assert leaves == ["leaf pass", "leaf pass"]
        page.wait_for_function("window.consoleView.tasks.played >= 1", timeout=30_000)
        end = page.evaluate("window.consoleView.map.drones.map(d => [d.x, d.y])")
        moved = [abs(a[0] - b[0]) + abs(a[1] - b[1]) for a, b in zip(start, end, strict=True)]
        assert max(moved) > 20  # the flight played on the map: a drone went to the point
        shot(page, "task-editor-proved")

        page.select_option("#editor-tool", "add obstacle circle")
        _click_world(page, x, y)
        _text(page, "#editor-status", "7 obstacles")
        check = _text(page, "#recheck-status", "re-check: 1 of 2 tasks solvable")
        assert "1 of 2" in check
        note = _text(page, "#task-check-0", "unsolvable")
        assert "checks[0] (drone_has_visited_position)" in note and "inside obstacle o7" in note
        assert (page.text_content("#task-check-1") or "") == "solvable"
        shot(page, "task-editor-rechecked")
        page.click("#undo")
        _text(page, "#recheck-status", "re-check: 2 of 2 tasks solvable")

        page.fill("#template-text", original.replace('"id": "photo_at_point"',
                                                     '"id": "my_photo"'))
        page.click("#template-save")
        saved_template = _text(page, "#template-status", "saved template my_photo")
        page.wait_for_selector("#template-pick optgroup[label='saved'] option[value='my_photo']",
                               state="attached")

        page.click("#template-new")  # writing one from the start
        page.click("#template-validate")
        _text(page, "#template-status", "valid template my_template")
        page.fill("#template-count", "1")
        page.click("#template-draw")
        _text(page, "#template-status", "drew 1 tasks of my_template")
        assert "drone on ground" in (page.text_content("#drawn-tree-0") or "")
        page.fill("#save-path", "sessions/with-tasks.json")
        page.click("#save")
        saved = _text(page, "#editor-status", "saved to")
    assert str(folder / "sessions" / "with-tasks.json") in saved
    template = folder / "templates" / "my_photo.json"
    assert str(template) in saved_template and json.loads(template.read_text())["id"] == "my_photo"
    session = load_session(folder / "sessions" / "with-tasks.json")
    assert [t.id for t in session.tasks] == ["t01", "t02"]
    assert all(t.template == "photo_at_point" and t.error is None for t in session.tasks)
    assert len(session.scenario.world.obstacles) == 6
