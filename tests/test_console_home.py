"""The console's home page and its bundle, in headless Chromium: the home page of `bench run
--web`'s console lists sessions that start after it was opened, without a reload; and where
the page's script was never built (a pip install of a checkout without npm), the page and the
commands that serve it say so and how to build it, instead of "loading..." forever."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from console.bench_watch import LiveBoard, serve_in_thread
from tests.browser_fixtures import open_page, shot
from tests.cli_fixtures import ROOT, read_until
from tests.ports import unused_tcp_port, unused_udp_port

pytestmark = [pytest.mark.browser]


def _scene(n: int) -> dict[str, Any]:
    return {"id": f"s{n}", "drones": [{"id": f"d{k}", "position": {"x": 10.0 * k, "y": 0.0,
                                                                    "z": 0.0}}
                                      for k in range(1, n + 1)],
            "targets": [], "obstacles": [], "map_size_m": [100, 100]}


def test_the_home_page_lists_sessions_that_start_after_it_opened(browser: Any) -> None:
    board = LiveBoard()
    with serve_in_thread(board, host="127.0.0.1", port=0, key="watch", rate_hz=5.0) as (url, _), \
            open_page(browser, f"{url}/?key=watch") as page:
        assert "no live swarm" in (page.text_content("#live-list") or "")
        board.update({"id": "first-trial0", "name": "First session", "scene": _scene(2)})
        page.wait_for_selector("a[href*='/live/first-trial0']", timeout=10_000)
        assert "First session (2 drones)" in (page.text_content("#live-list") or "")
        board.update({"id": "second-trial0", "name": "Second session", "scene": _scene(3)})
        page.wait_for_selector("a[href*='/live/second-trial0']", timeout=10_000)
        assert page.locator("#live-list a").count() == 2
        href = page.get_attribute("a[href*='/live/second-trial0']", "href") or ""
        assert href.endswith("?key=watch")
        shot(page, "home-new-sessions")


@pytest.fixture(scope="module")
def unbuilt(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """An environment whose `console` package has no bundle (static/app.js), as a pip install
    of a checkout without npm has."""
    root = tmp_path_factory.mktemp("unbuilt")
    shutil.copytree(ROOT / "console", root / "console",
                    ignore=shutil.ignore_patterns("web", "app.js", "__pycache__"))
    assert not (root / "console" / "static" / "app.js").exists()
    return {**os.environ, "PYTHONPATH": f"{root}{os.pathsep}{ROOT}", "PYTHONUNBUFFERED": "1"}


def _mavswarm(env: dict[str, str], cwd: Path, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, "-m", "mavswarm", *args], cwd=cwd, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def test_an_unbuilt_page_says_how_to_build_it(browser: Any, unbuilt: dict[str, str],
                                              tmp_path: Path) -> None:
    results = tmp_path / "results"
    results.mkdir()
    (results / "results.jsonl").write_text("")
    port = unused_tcp_port()
    proc = _mavswarm(unbuilt, tmp_path, "replay", str(results), "--port", str(port))
    try:
        printed = read_until(proc, "npm ci", 30)
        assert "run inspector: http://" in printed
        assert "not built" in printed and "npm ci && npm run build" in printed
        with open_page(browser, f"http://127.0.0.1:{port}/runs") as page:
            assert page.get_attribute("body", "data-not-built") == "1"
            text = page.text_content("#app") or ""
            assert "not built" in text and "npm ci && npm run build" in text and "./dev" in text
            assert "loading" not in text
            shot(page, "not-built")
    finally:
        proc.terminate()
        proc.wait(10)


def test_up_web_says_the_page_is_not_built(unbuilt: dict[str, str], tmp_path: Path) -> None:
    proc = _mavswarm(unbuilt, tmp_path, "up", "--drones", "1", "--no-truth", "--web",
                     "--web-port", str(unused_tcp_port()), "--api-port", str(unused_udp_port()),
                     "--gcs-port", "0", "--bind-port", str(unused_udp_port()))
    try:
        printed = read_until(proc, "npm ci", 60)  # not "npm": a random key may hold it
        assert "web console: http://" in printed
        assert "the web console's page is not built" in printed
    finally:
        proc.terminate()
        proc.wait(10)
