"""`mavswarm bench run --web` in headless Chromium: with two workers, the console lists both
sessions being run; the one picked shows its drones live, with the task being flown."""

from __future__ import annotations

import json
import os
import subprocess
import time
from pathlib import Path
from typing import Any

import httpx
import pytest

from tests.browser_fixtures import open_page, shot
from tests.cli_fixtures import MAVSWARM, ROOT, read_until
from tests.ports import unused_tcp_port

pytestmark = [pytest.mark.browser, pytest.mark.mavsdk]


def test_bench_run_web_follows_the_session_picked(browser: Any, tmp_path: Path) -> None:
    paths = []
    for k, name in enumerate(("area_search-easy-1", "target_assignment-easy-1")):
        data = json.loads((ROOT / "benchmark" / "sessions" / f"{name}.json").read_text())
        data["tasks"] = data["tasks"][:8]
        paths.append(tmp_path / f"s{k}.json")
        paths[-1].write_text(json.dumps(data))
    port = unused_tcp_port()
    proc = subprocess.Popen(
        [*MAVSWARM, "bench", "run", "--agent", "oracle", "--sessions", *map(str, paths),
         "--workers", "2", "--out", str(tmp_path / "run"), "--web", "--web-port", str(port),
         "--web-key", "watch", "--web-exit"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
        text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        printed = read_until(proc, "web console:", 60)
        assert f"http://127.0.0.1:{port}/?key=watch" in printed
        base = f"http://127.0.0.1:{port}"
        assert httpx.get(f"{base}/api/info").status_code == 401
        deadline = time.monotonic() + 60
        while len(httpx.get(f"{base}/api/info", headers={"X-API-Key": "watch"})
                  .json()["live"]) < 2:
            assert time.monotonic() < deadline, "the two sessions never showed up"
            time.sleep(0.2)
        with open_page(browser, f"{base}/?key=watch") as page:
            links = page.locator("a[href*='/live/']")
            assert links.count() == 2
            assert "target_assignment-easy-1-trial0" in (
                links.nth(0).get_attribute("href") or "") + (
                links.nth(1).get_attribute("href") or "")
            shot(page, "bench-watch-home")
            page.locator("a[href*='target_assignment-easy-1-trial0']").click()
            page.wait_for_selector("body[data-ready='1']")
            page.wait_for_function("window.consoleView && window.consoleView.state.frames >= 3",
                                   timeout=30_000)
            assert len(page.evaluate("window.consoleView.state.drones")) == 3
            page.wait_for_function("document.getElementById('live-task').textContent.length > 0",
                                   timeout=30_000)
            assert page.locator("#commands button").count() == 0  # watching only
            shot(page, "bench-watch-live")
        assert proc.wait(240) == 0
    finally:
        if proc.poll() is None:
            proc.terminate()
            proc.wait(10)
    records = (tmp_path / "run" / "results.jsonl").read_text().splitlines()
    assert len(records) == 16
