"""Driving the web console in a real browser: Debian's headless Chromium through Playwright
(the system executable; Playwright's own browser download is never used), an asyncio loop in
a thread for in-process swarms and servers, and what a person would check on the 2D map: is a
drone drawn at the pixel where the ground truth puts it.

Screenshots go to `artifacts/console/` (gitignored), one per view.
"""

from __future__ import annotations

import asyncio
import contextlib
import shutil
import threading
from collections.abc import Coroutine, Iterator
from pathlib import Path
from typing import Any, TypeVar

import pytest

from tests.cli_fixtures import ROOT

__all__ = [
    "ARTIFACTS",
    "CHROMIUM_ARGS",
    "DRONE_RGB",
    "LoopThread",
    "chromium_path",
    "drone_pixels_near",
    "map_view",
    "open_page",
    "screen_of",
    "shot",
    "webgl_colours",
]

T = TypeVar("T")
ARTIFACTS = ROOT / "artifacts" / "console"
DRONE_RGB = (230, 0, 126)  # the map's drone colour (console/web/src/map2d.js)
# WebGL on SwiftShader (there is no GPU); the page's layers composited on the CPU, as Chromium
# does on a machine without a GPU (compositing every frame through SwiftShader costs twice the
# CPU and slows every other test running beside it).
CHROMIUM_ARGS = ["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                 "--disable-gpu-compositing"]


def chromium_path() -> str:
    """Debian's chromium (installed by .ci/run); the test is skipped, saying so, without it."""
    found = shutil.which("chromium") or shutil.which("chromium-browser")
    if found is None:
        pytest.skip("Debian's chromium is not installed (.ci/run installs it with apt-get)")
    return found


class LoopThread:
    """An asyncio loop running in a daemon thread; `run(coro)` waits for its result."""

    def __init__(self) -> None:
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self.loop.run_forever, daemon=True)
        self._thread.start()

    def run(self, coro: Coroutine[Any, Any, T], timeout_s: float = 60.0) -> T:
        return asyncio.run_coroutine_threadsafe(coro, self.loop).result(timeout_s)

    def close(self) -> None:
        self.loop.call_soon_threadsafe(self.loop.stop)
        self._thread.join(10)


@contextlib.contextmanager
def open_page(browser: Any, url: str, *, ready: bool = True) -> Iterator[Any]:
    """A page at `url` (1500 x 900), waiting until the console says it is ready."""
    page = browser.new_page(viewport={"width": 1500, "height": 900})
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    try:
        page.goto(url)
        if ready:
            page.wait_for_selector("body[data-ready='1']", timeout=30_000)
        yield page
        assert not errors, errors
    finally:
        page.close()


def shot(page: Any, name: str) -> Path:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    path = ARTIFACTS / f"{name}.png"
    page.screenshot(path=str(path))
    return path


def map_view(page: Any) -> dict[str, float]:
    """The 2D map's view transform as the page holds it."""
    return page.evaluate("() => { const m = window.consoleView.map; return {scale: m.view.scale,"
                         " cx: m.view.cx, cy: m.view.cy, width: m.width, height: m.height,"
                         " dpr: m.dpr}; }")


def screen_of(view: dict[str, float], x_m: float, y_m: float) -> tuple[float, float]:
    """Where world point (x east, y north) is on the map canvas, in CSS pixels, north up."""
    return (view["width"] / 2 + (x_m - view["cx"]) * view["scale"],
            view["height"] / 2 - (y_m - view["cy"]) * view["scale"])


def drone_pixels_near(page: Any, x_m: float, y_m: float, radius_px: int = 3) -> int:
    """How many pixels of the drone colour the 2D map shows within radius_px of the point."""
    view = map_view(page)
    sx, sy = screen_of(view, x_m, y_m)
    return int(page.evaluate(
        """([sx, sy, r, rgb]) => {
            const m = window.consoleView.map;
            m.draw();
            const d = m.dpr, x0 = Math.round((sx - r) * d), y0 = Math.round((sy - r) * d);
            const size = Math.max(1, Math.round(2 * r * d));
            const data = m.ctx.getImageData(x0, y0, size, size).data;
            let hits = 0;
            for (let k = 0; k < data.length; k += 4) {
                if (Math.abs(data[k] - rgb[0]) < 12 && data[k + 1] < 25
                        && Math.abs(data[k + 2] - rgb[2]) < 20) hits++;
            }
            return hits;
        }""", [sx, sy, radius_px, list(DRONE_RGB)]))


def webgl_colours(page: Any) -> int:
    """Distinct colours on the 3D view's canvas (a blank canvas has one)."""
    page.wait_for_function("window.consoleView.view3d", timeout=20_000)
    return int(page.evaluate(
        """() => {
            const gl = document.querySelector('#view3d canvas');
            window.consoleView.view3d.render();
            const c = document.createElement('canvas');
            c.width = gl.width; c.height = gl.height;
            const ctx = c.getContext('2d');
            ctx.drawImage(gl, 0, 0);
            const data = ctx.getImageData(0, 0, c.width, c.height).data;
            const seen = new Set();
            for (let k = 0; k < data.length; k += 64) {
                seen.add((data[k] << 16) | (data[k + 1] << 8) | data[k + 2]);
            }
            return seen.size;
        }"""))
