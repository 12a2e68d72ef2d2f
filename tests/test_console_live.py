"""The live view in headless Chromium against real swarms: drones drawn where the ground truth
puts them, trails that grow as they fly, a 3D view that is not blank, operator commands
(take off, fly to a clicked point) that move the drone in the truth over MAVLink, and the keys
that may open it (operator and admin yes, agent no, none no)."""

from __future__ import annotations

import asyncio
import contextlib
import io
import json
import math
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from benchmark.server.serve import serve_rest
from console.cli import console_for_hub
from emulator.swarm import Swarm
from tests.browser_fixtures import (
    LoopThread,
    drone_pixels_near,
    open_page,
    shot,
    webgl_colours,
)
from tests.cli_fixtures import ROOT
from tests.console_server import swarm_with_console
from tests.ports import unused_tcp_port

pytestmark = [pytest.mark.browser, pytest.mark.mavsdk]

KEY = "operator-key-for-tests"
SPOTS = [(0.0, 0.0), (60.0, 0.0), (0.0, 70.0)]


@pytest.fixture(scope="module")
def live() -> Iterator[tuple[Swarm, str]]:
    """Three drones spread apart, 5x real time, with the console of `up --web`."""
    with swarm_with_console(SPOTS, KEY) as served:
        yield served


def _truth(swarm: Swarm, drone: str) -> tuple[float, float, float]:
    x, y, z = swarm.fleet.dyn.position_m[swarm.fleet.index_by_id[drone]]
    return float(x), float(y), float(z)


def _wait_text(page: Any, selector: str, text: str, timeout_s: float = 90.0) -> str:
    deadline = time.monotonic() + timeout_s
    content = ""
    while time.monotonic() < deadline:
        content = page.text_content(selector) or ""
        if text in content:
            return content
        time.sleep(0.1)
    raise AssertionError(f"{selector} never showed {text!r}; it shows {content!r}")


def test_live_view_draws_the_truth_and_commands_fly_the_drone(browser: Any,
                                                               live: tuple[Swarm, str]) -> None:
    swarm, url = live
    with open_page(browser, f"{url}/live/swarm?key={KEY}") as page:
        page.wait_for_function("window.consoleView.state.frames >= 3", timeout=20_000)
        for drone in ("d1", "d2", "d3"):
            x, y, _ = _truth(swarm, drone)
            assert drone_pixels_near(page, x, y) >= 8, f"{drone} is not drawn at ({x}, {y})"
        assert drone_pixels_near(page, 30.0, 35.0) == 0  # nothing drawn between them
        assert webgl_colours(page) >= 20
        # Chromium here renders WebGL on SwiftShader (no GPU): the 3D view knows it and draws
        # without multisampling, which costs several times a plain frame on the CPU.
        assert page.evaluate("window.consoleView.view3d.software") is True
        assert page.evaluate("window.consoleView.view3d.renderer.getContext()"
                             ".getContextAttributes().antialias") is False
        shot(page, "live-before")

        page.click(".drone-row[data-drone='d1'] .drone-id")
        page.fill("#cmd-altitude", "12")
        page.click("#cmd-take_off")
        _wait_text(page, ".drone-row[data-drone='d1'] .drone-outcome", "take_off: ok")
        assert _truth(swarm, "d1")[2] == pytest.approx(12.0, abs=1.0)
        trail_before = page.evaluate("window.consoleView.state.trails.get('d1').length")

        target = (80.0, 45.0)
        page.click("#cmd-fly")
        box = page.locator("#map2d").bounding_box()
        view = page.evaluate("() => { const m = window.consoleView.map; return [m.view.scale,"
                             " m.view.cx, m.view.cy, m.width, m.height]; }")
        scale, cx, cy, width, height = view
        sx, sy = width / 2 + (target[0] - cx) * scale, height / 2 - (target[1] - cy) * scale
        page.mouse.click(box["x"] + sx, box["y"] + sy)
        _wait_text(page, ".drone-row[data-drone='d1'] .drone-outcome", "move_to: ok")
        x, y, z = _truth(swarm, "d1")
        assert math.hypot(x - target[0], y - target[1]) < 3.0, (x, y)  # within one pixel
        assert z == pytest.approx(12.0, abs=1.0)
        page.wait_for_timeout(500)
        assert drone_pixels_near(page, x, y) >= 8
        assert page.evaluate("window.consoleView.state.trails.get('d1').length") > \
            trail_before + 5
        panel = page.text_content("#drone-panel") or ""
        assert "move_to" in panel and "ok" in panel
        shot(page, "live-after-fly-to")


def test_the_live_view_needs_the_operator_key(browser: Any, live: tuple[Swarm, str]) -> None:
    _, url = live
    assert httpx.get(f"{url}/api/info").status_code == 401
    assert httpx.get(f"{url}/api/info", headers={"X-API-Key": "wrong"}).status_code == 401
    assert httpx.get(f"{url}/api/info", headers={"X-API-Key": KEY}).status_code == 200
    refused = httpx.post(f"{url}/api/live/swarm/command", json={"drone_id": "d2",
                                                                "tool": "take_photo"},
                         headers={"X-API-Key": KEY})
    assert refused.status_code == 422 and "not a console command" in refused.json()["message"]
    with open_page(browser, f"{url}/live/swarm") as page:
        assert "401" in (page.text_content("#error") or "")


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, dict[str, Any]]]:
    """`mavswarm serve` of one session with the console mounted, agent/operator/admin keys."""
    source = json.loads((ROOT / "benchmark/sessions/area_search-easy-1.json").read_text())
    source["tasks"] = source["tasks"][:1]
    path: Path = tmp_path_factory.mktemp("serve") / "mini.json"
    path.write_text(json.dumps(source))
    loop = LoopThread()
    port = unused_tcp_port()
    ready: asyncio.Future[str] = loop.loop.create_future()

    async def run() -> None:
        await serve_rest([path], port=port, keys=["agent=ak", "operator=ok", "admin=adm"],
                         out=io.StringIO(), extend=console_for_hub,
                         on_ready=lambda url: ready.set_result(url))

    task = asyncio.run_coroutine_threadsafe(run(), loop.loop)
    try:
        yield loop.run(asyncio.wait_for(asyncio.shield(ready), 60)), source
    finally:
        task.cancel()
        with contextlib.suppress(BaseException):
            task.result(30)
        loop.close()


def test_serve_mounts_the_console_for_operators_and_admins_only(
        browser: Any, served: tuple[str, dict[str, Any]]) -> None:
    url, source = served
    base = f"{url}/console"
    assert httpx.get(f"{base}/api/info", headers={"X-API-Key": "ak"}).status_code == 403
    assert httpx.get(f"{base}/api/info", headers={"X-API-Key": "adm"}).status_code == 200
    with open_page(browser, f"{base}/live/area_search-easy-1?key=ak") as page:
        assert "403" in (page.text_content("#error") or "")
    with open_page(browser, f"{base}/live/area_search-easy-1?key=ok") as page:
        page.wait_for_function("window.consoleView.state.frames >= 2", timeout=20_000)
        assert len(page.evaluate("window.consoleView.state.drones")) == 3
        for drone in source["drones"]:  # at rest where the session file puts them
            spot = drone["position"]
            assert drone_pixels_near(page, spot["x"], spot["y"], radius_px=4) >= 8, drone["id"]
        assert "Fly" in (page.text_content("#commands") or "")
        shot(page, "serve-live")
