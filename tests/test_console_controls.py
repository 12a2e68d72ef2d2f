"""Live control from the console as a pilot uses it, in headless Chromium against a real swarm
over MAVLink (the console of `up --web`): commands for a selection or all drones, each drone's
last outcome under it in the drone list; a fly-to that replaces the goal of a drone already
flying one (the first ends `interrupted`), Stop/Hold that halts a drone mid-flight, a landing
that replaces a fly-to; and the fly-to marker drawn only for a drone that accepted the
command (a drone on the ground refuses it, and no marker appears)."""

from __future__ import annotations

import math
import re
import time
from collections.abc import Iterator
from typing import Any

import httpx
import numpy as np
import pytest

from emulator.swarm import Swarm
from tests.browser_fixtures import map_view, open_page, screen_of, shot
from tests.console_server import swarm_with_console

pytestmark = [pytest.mark.browser, pytest.mark.mavsdk]

KEY = "pilot-key"
SPOTS = [(0.0, 0.0), (30.0, 0.0), (0.0, 30.0), (30.0, 30.0)]


@pytest.fixture(scope="module")
def live() -> Iterator[tuple[Swarm, str]]:
    """Four drones 30 m apart, 5x real time, with the console of `up --web`."""
    with swarm_with_console(SPOTS, KEY) as served:
        yield served


def _truth(swarm: Swarm, drone: str) -> tuple[float, float, float]:
    x, y, z = swarm.fleet.dyn.position_m[swarm.fleet.index_by_id[drone]]
    return float(x), float(y), float(z)


def _settled(swarm: Swarm, drones: tuple[str, ...], timeout_s: float = 60.0) -> None:
    """Wait until `drones` are still (what an earlier test of the module set going is over)."""
    deadline = time.monotonic() + timeout_s
    rows = [swarm.fleet.index_by_id[d] for d in drones]
    while max(float(np.linalg.norm(swarm.fleet.dyn.velocity_m_s[k])) for k in rows) > 0.05:
        assert time.monotonic() < deadline, "the drones did not come to rest"
        time.sleep(0.1)


def _row(page: Any, drone: str, text: str, timeout_s: float = 60.0) -> str:
    """Wait until `drone`'s last outcome in the drone list shows `text`."""
    selector = f".drone-row[data-drone='{drone}'] .drone-outcome"
    deadline = time.monotonic() + timeout_s
    shown = ""
    while time.monotonic() < deadline:
        shown = page.text_content(selector) or ""
        if text in shown:
            return shown
        time.sleep(0.05)
    raise AssertionError(f"{drone}'s outcome never showed {text!r}; it shows {shown!r}")


def _result(page: Any, text: str, timeout_s: float = 30.0) -> str:
    """Wait until the answer to the last command shows `text`."""
    deadline = time.monotonic() + timeout_s
    shown = ""
    while time.monotonic() < deadline:
        shown = page.text_content("#cmd-result") or ""
        if text in shown:
            return shown
        time.sleep(0.05)
    raise AssertionError(f"the command's answer never showed {text!r}; it shows {shown!r}")


def _click_world(page: Any, x_m: float, y_m: float) -> None:
    box = page.locator("#map2d").bounding_box()
    sx, sy = screen_of(map_view(page), x_m, y_m)
    page.mouse.click(box["x"] + sx, box["y"] + sy)


def _fly_to(page: Any, x_m: float, y_m: float) -> None:
    page.click("#cmd-fly")
    _click_world(page, x_m, y_m)


def _markers(page: Any) -> dict[str, Any]:
    """The fly-to markers on the map: drone -> its target (to within a pixel's metres)."""
    shown = page.evaluate("Object.fromEntries([...window.consoleView.state.markers]"
                          ".map(([id, m]) => [id, [m.x, m.y]]))")
    return {drone: pytest.approx(xy, abs=2.0) for drone, xy in shown.items()}


def _pick(page: Any, *drones: str) -> None:
    page.click("#pick-none")
    for drone in drones:
        page.check(f".drone-row[data-drone='{drone}'] input.pick")


def test_a_pilot_commands_a_selection_replaces_goals_and_holds(
        browser: Any, live: tuple[Swarm, str]) -> None:
    swarm, url = live
    with open_page(browser, f"{url}/live/swarm?key={KEY}") as page:
        page.wait_for_function("window.consoleView.state.frames >= 3", timeout=20_000)
        assert "point obstacle" in (page.text_content(".legend") or "")
        assert "null" not in (page.text_content("#commands") or "")
        assert page.query_selector("#cmd-refusal") is None  # `up --web` takes commands
        # A fly-to for a drone on the ground is refused at once: no marker.
        _pick(page, "d4")
        _fly_to(page, 200.0, 40.0)
        assert "rejected" in _result(page, "move_to: rejected")
        _row(page, "d4", "move_to: rejected")
        assert _markers(page) == {}

        # Three of four drones take off together, each outcome under its drone.
        _pick(page, "d1", "d2", "d3")
        assert "d1, d2, d3" in (page.text_content("#cmd-target") or "")
        page.fill("#cmd-altitude", "8")
        page.click("#cmd-take_off")
        for drone in ("d1", "d2", "d3"):
            _row(page, drone, "take_off: ok")
            assert _truth(swarm, drone)[2] == pytest.approx(8.0, abs=1.0)
        assert _truth(swarm, "d4")[2] == pytest.approx(0.0, abs=0.2)

        # d1 flies far; a second fly-to replaces that goal instead of "busy: wait".
        _pick(page, "d1")
        _fly_to(page, 300.0, 0.0)
        first = _result(page, "move_to: accepted")
        assert "d1" in first
        assert _markers(page) == {"d1": [300.0, 0.0]}
        time.sleep(0.5)
        _fly_to(page, 0.0, 250.0)
        _result(page, "move_to: accepted")
        assert _markers(page) == {"d1": [0.0, 250.0]}
        _row(page, "d1", "move_to: interrupted")
        executing = page.text_content(".drone-row[data-drone='d1'] .drone-executing") or ""
        going = re.search(r"move_to\(x=([-\d.]+), y=([-\d.]+)", executing)
        assert going is not None, executing
        assert float(going.group(2)) == pytest.approx(250.0, abs=2.0)
        shot(page, "controls-replaced-goal")

        # A command that does not replace goals is refused while one runs, which runs on.
        page.click("#cmd-hover")
        _row(page, "d1", "hover: rejected")
        assert "busy with move_to" in _row(page, "d1", "hover: rejected")
        executing = page.text_content(".drone-row[data-drone='d1'] .drone-executing") or ""
        assert "move_to(" in executing

        # Stop/Hold halts it mid-flight, far from the goal.
        time.sleep(0.6)
        page.click("#cmd-hold")
        assert "move_to interrupted" in _row(page, "d1", "hold: ok")
        page.wait_for_timeout(800)  # 4 s simulated: any drift would show
        held = _truth(swarm, "d1")
        page.wait_for_timeout(1000)
        still = _truth(swarm, "d1")
        assert math.dist(held, still) < 0.5, (held, still)
        assert math.dist(still[:2], (0.0, 250.0)) > 20.0
        assert "d1" not in _markers(page)  # its goal is gone

        # A landing replaces a fly-to in progress. Where d1 held depends on wall time (on a
        # loaded machine it flew further east first): a goal to the north-west keeps its way
        # clear of every obstacle (point obstacle o1 at (120, 60) lay on the way to (150, 150)).
        _fly_to(page, -40.0, 120.0)
        _result(page, "move_to: accepted")
        time.sleep(0.4)
        page.click("#cmd-land")
        _row(page, "d1", "land: ok")
        assert _truth(swarm, "d1")[2] == pytest.approx(0.0, abs=0.3)
        assert "d1" not in _markers(page)
        shot(page, "controls-landed")

        # Hold all stops every drone in the air; a selection flies keeping its shape.
        _pick(page, "d2", "d3")
        _fly_to(page, 115.0, 115.0)  # their centre (15, 15) + 100 m each way
        _result(page, "move_to: d2 accepted; d3 accepted")
        assert _markers(page) == {"d2": [130.0, 100.0], "d3": [100.0, 130.0]}
        time.sleep(0.5)
        page.click("#cmd-hold-all")
        for drone in ("d2", "d3"):
            _row(page, drone, "hold: ok")
        for drone in ("d1", "d4"):  # on the ground: nothing to hold
            _row(page, drone, "hold: ok")
        assert _markers(page) == {}


def test_selection_commands_are_checked_whole_before_anything_is_sent(
        live: tuple[Swarm, str]) -> None:
    swarm, url = live
    post = f"{url}/api/live/swarm/command"
    headers = {"X-API-Key": KEY}
    _settled(swarm, ("d1", "d2", "d3", "d4"))
    before = {d: _truth(swarm, d) for d in ("d1", "d2", "d3", "d4")}
    unknown = httpx.post(post, json={"drone_ids": ["d2", "d9"], "tool": "hold"},
                         headers=headers)
    assert unknown.status_code == 404 and "d9" in unknown.json()["detail"]
    bad = httpx.post(post, json={"drone_ids": "all", "tool": "take_off",
                                 "args_by_drone": {"d3": {"altitude_m": "high"}},
                                 "args": {"altitude_m": 5}}, headers=headers)
    assert bad.status_code == 422 and bad.json()["message"].startswith("d3: take_off:")
    odd = httpx.post(post, json={"drone_ids": "all", "tool": "hold", "args": {"x": 1}},
                     headers=headers)
    assert odd.status_code == 422 and "hold takes no arguments" in odd.json()["message"]
    none = httpx.post(post, json={"drone_ids": [], "tool": "hold"}, headers=headers)
    assert none.status_code == 422
    nan = httpx.post(post, content=b'{"drone_id": "d1", "tool": "take_off", '
                                   b'"args": {"altitude_m": NaN}}', headers=headers)
    assert nan.status_code == 422
    time.sleep(0.5)
    after = {d: _truth(swarm, d) for d in before}
    for drone, spot in before.items():
        assert math.dist(spot, after[drone]) < 0.5, drone
