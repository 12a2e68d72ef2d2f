"""The 2D map stays readable where drones crowd, in headless Chromium: the shipped session with
30 drones at one base (area_assignment_and_patrol-extreme-1, 1.5 km map) opened in the editor.
Drone labels never overprint each other or a drone; at the zoom that fits the map the crowd is
one cluster whose badge counts it and whose label names it; zoomed in, the clusters split and
more drones are labelled, still without overprinting. A point obstacle (a mast) is a crossed
square, with no drone colour where it stands."""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any

import pytest

from console.app import ConsoleState
from console.auth import ConsoleAuth
from tests.browser_fixtures import drone_pixels_near, map_view, open_page, screen_of, shot
from tests.cli_fixtures import ROOT
from tests.console_server import serve_console

pytestmark = [pytest.mark.browser]

CROWDED = "area_assignment_and_patrol-extreme-1"


@pytest.fixture(scope="module")
def console_url(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    state = ConsoleState(ConsoleAuth(lambda _key: None, open_access=True),
                         editor_root=tmp_path_factory.mktemp("editor"))
    with serve_console(state) as url:
        yield url


def _open_crowded(page: Any) -> None:
    page.wait_for_function("(document.getElementById('editor-status').textContent || '')"
                           ".includes('valid')", timeout=15_000)
    page.select_option("#start-source", "shipped")
    page.select_option("#start-shipped", CROWDED)
    page.click("#start-load")
    page.wait_for_function("window.consoleView.state.session.drones.length === 30",
                           timeout=15_000)
    page.wait_for_timeout(300)


def _overlap(a: dict[str, float], b: dict[str, float]) -> bool:
    return (a["x"] < b["x"] + b["w"] and b["x"] < a["x"] + a["w"]
            and a["y"] < b["y"] + b["h"] and b["y"] < a["y"] + a["h"])


def _layout(page: Any) -> tuple[list[dict[str, Any]], list[dict[str, Any]],
                                list[tuple[float, float]]]:
    """The map's label boxes, clusters and drone dots (screen pixels) after a fresh draw."""
    page.evaluate("window.consoleView.map.draw()")
    labels = page.evaluate("window.consoleView.map.labelBoxes")
    clusters = page.evaluate("window.consoleView.map.clusters")
    view = map_view(page)
    drones = page.evaluate("window.consoleView.map.drones.map(d => [d.x, d.y])")
    return labels, clusters, [screen_of(view, x, y) for x, y in drones]


def _assert_readable(labels: list[dict[str, Any]], dots: list[tuple[float, float]]) -> None:
    for k, a in enumerate(labels):
        for b in labels[k + 1:]:
            assert not _overlap(a, b), f"labels {a['text']!r} and {b['text']!r} overprint"
        for sx, sy in dots:
            dot = {"x": sx - 6, "y": sy - 6, "w": 12, "h": 12}
            assert not _overlap(a, dot), f"label {a['text']!r} covers a drone at {sx, sy}"


def test_crowded_drones_are_clustered_and_labels_never_overprint(
        browser: Any, console_url: str) -> None:
    with open_page(browser, f"{console_url}/editor") as page:
        _open_crowded(page)
        labels, clusters, dots = _layout(page)
        _assert_readable(labels, dots)
        assert len(clusters) == 1 and len(clusters[0]["ids"]) == 30  # the base, one badge
        assert labels and labels[0]["text"] == "d1, d2 +28"
        shot(page, "map-crowded-fit")

        box = page.locator("#map2d").bounding_box()
        centre = screen_of(map_view(page), 1430.0, 1430.0)
        page.mouse.move(box["x"] + centre[0], box["y"] + centre[1])
        for _ in range(3):
            page.mouse.wheel(0, -300)
            page.wait_for_timeout(60)
        labels, clusters, dots = _layout(page)
        _assert_readable(labels, dots)
        assert 10 < len(clusters) < 30 and len(labels) >= 10
        named = {d for label in labels for d in label["ids"]}
        assert len(named) >= 20, named
        shot(page, "map-crowded-zoomed")

        for _ in range(3):
            page.mouse.wheel(0, -300)
            page.wait_for_timeout(60)
        labels, clusters, dots = _layout(page)
        _assert_readable(labels, dots)
        assert len(clusters) == 30  # close enough to tell every drone apart
        assert all(len(label["ids"]) == 1 for label in labels)


def test_a_click_on_a_cluster_badge_zooms_into_it(browser: Any, console_url: str) -> None:
    with open_page(browser, f"{console_url}/editor") as page:
        _open_crowded(page)
        scale = map_view(page)["scale"]
        badge = page.evaluate("window.consoleView.map._badges[0]")
        assert len(badge["ids"]) == 30
        box = page.locator("#map2d").bounding_box()
        page.mouse.click(box["x"] + badge["x"], box["y"] + badge["y"])
        assert map_view(page)["scale"] == pytest.approx(4 * scale)
        assert page.evaluate("window.consoleView.state.selected") is None  # nothing picked
        _, clusters, _ = _layout(page)
        assert len(clusters) > 1


def test_a_point_obstacle_is_a_crossed_square_not_a_dot(browser: Any, console_url: str) -> None:
    session = json.loads((ROOT / "benchmark/sessions" / f"{CROWDED}.json").read_text())
    masts = [o for o in session["obstacles"] if o["type"] == "point"]
    assert len(masts) == 5
    with open_page(browser, f"{console_url}/editor") as page:
        _open_crowded(page)
        view = map_view(page)
        for mast in masts:
            x, y = mast["position"]["x"], mast["position"]["y"]
            assert drone_pixels_near(page, x, y, radius_px=6) == 0, mast["id"]
            sx, sy = screen_of(view, x, y)
            white, dark = page.evaluate(
                """([sx, sy]) => {
                    const m = window.consoleView.map, d = m.dpr;
                    const data = m.ctx.getImageData(Math.round((sx - 5) * d),
                        Math.round((sy - 5) * d), Math.round(10 * d), Math.round(10 * d)).data;
                    let white = 0, dark = 0;
                    for (let k = 0; k < data.length; k += 4) {
                        if (data[k] > 240 && data[k + 1] > 240 && data[k + 2] > 240) white++;
                        if (data[k] < 110 && data[k + 1] < 110 && data[k + 2] < 130) dark++;
                    }
                    return [white, dark];
                }""", [sx, sy])
            assert white >= 8 and dark >= 8, (mast["id"], white, dark)  # white box, dark cross
        shot(page, "map-point-obstacles")
