"""Two plug-in agents (`--agent file.py:Name`) flown by `mavswarm bench run` over MAVSDK on one
session of four take-off tasks: one flies tasks 1 and 2, the other tasks 2 and 3. `mavswarm
bench compare` of the two results folders reports exactly that: task 1 pass->fail, task 2
both pass, task 3 fail->pass, task 4 both fail. Served by `mavswarm replay`, the console's
compare view plays task 1 of both runs side by side on one timeline (headless Chromium)."""

from __future__ import annotations

import json
import os
import subprocess
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest

from tests.bench_fixtures import small_session, write_json
from tests.browser_fixtures import open_page, shot
from tests.cli_fixtures import MAVSWARM, read_until, run_in_process
from tests.ports import unused_tcp_port

pytestmark = [pytest.mark.mavsdk, pytest.mark.slow, pytest.mark.browser]

PLUGIN = '''"""Take-off agents for the comparison test: each flies its own tasks' take-off."""

PLANS = {plans!r}


class Flies:
    FLY: tuple[str, ...] = ()

    async def run(self, task, tools):
        if task.task_id in self.FLY:
            drone, altitude_m = PLANS[task.task_id]
            await tools.take_off(drone, altitude_m)
        tools.finish("done")


class FliesOneTwo(Flies):
    FLY = ("t01", "t02")


class FliesTwoThree(Flies):
    FLY = ("t02", "t03")
'''


def _mavswarm(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """`mavswarm ARGS` by the command's `main` in this process (the replay server below is a
    process of its own), on a thread of its own: the browser's event loop runs on this one."""
    with ThreadPoolExecutor(1) as pool:
        return pool.submit(run_in_process, *args, cwd=cwd).result()


def test_compare_of_two_plugin_agents_reports_exactly_their_differences(
        browser: Any, tmp_path: Path) -> None:
    data = small_session(["takeoff_hold"] * 4)
    plans = {t["id"]: (t["oracle"][0][0]["drone"], t["oracle"][0][0]["altitude_m"])
             for t in data["tasks"]}
    session = write_json(tmp_path / "s.json", data)
    plugin = tmp_path / "takeoff_agents.py"
    plugin.write_text(PLUGIN.format(plans=plans), encoding="utf-8")
    for name, out in (("FliesOneTwo", "one_two"), ("FliesTwoThree", "two_three")):
        done = _mavswarm("bench", "run", "--agent", f"{plugin}:{name}",
                         "--sessions", str(session), "--out", str(tmp_path / out), cwd=tmp_path)
        assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    done = _mavswarm("bench", "compare", str(tmp_path / "one_two"),
                     str(tmp_path / "two_three"), "--out", str(tmp_path / "cmp"), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert ("two_three vs one_two: 1 fail->pass, 1 pass->fail, 1 both pass, 1 both fail"
            in done.stdout)
    report = json.loads((tmp_path / "cmp" / "compare.json").read_text())
    (pair,) = report["pairs"]
    assert {(c["task"], c["change"]) for c in pair["changed"]} == {
        ("t01", "pass_to_fail"), ("t03", "fail_to_pass")}
    assert pair["overall"]["mcnemar_p"] == 1.0
    runs = {r["id"]: r for r in report["runs"]}
    assert runs["one_two"]["agent"].endswith(":FliesOneTwo")
    assert runs["one_two"]["passed_tasks"] == runs["two_three"]["passed_tasks"] == 2
    assert runs["one_two"]["clocks"] == ["lockstep"]
    _replays_side_by_side(browser, tmp_path, data["id"])


def _replays_side_by_side(browser: Any, work: Path, session: str) -> None:
    port = unused_tcp_port()
    proc = subprocess.Popen([*MAVSWARM, "replay", str(work / "one_two"), str(work / "two_three"),
                             "--port", str(port)], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True,
                            env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        read_until(proc, "http://", 30)
        base = f"http://127.0.0.1:{port}"
        with open_page(browser, f"{base}/compare?a=one_two&b=two_three") as page:
            page.locator("#compare-table a.side-by-side").first.click()
            page.wait_for_selector("#side-b canvas#map2d", timeout=30_000)
            assert page.evaluate("window.consoleView.records.map(r => r.passed)") == [True,
                                                                                      False]
            assert page.evaluate("window.consoleView.players.length") == 2
            # Run B finished at once: its window is the one settling second; A's is longer.
            spans = page.evaluate("window.consoleView.players.map(p => p.t1 - p.t0)")
            assert spans[0] > spans[1] > 0.5
            page.evaluate("(() => { const p = window.consoleView.players[0];"
                          " p.seek(p.t0 + 0.5); })()")
            offsets = page.evaluate("window.consoleView.players.map(p => p.t - p.t0)")
            assert offsets == [pytest.approx(0.5), pytest.approx(0.5)]
            page.locator("#side-b #replay-slider").fill("1000")  # B to its end: A follows
            offsets = page.evaluate("window.consoleView.players.map(p => p.t - p.t0)")
            assert offsets == [pytest.approx(spans[1]), pytest.approx(spans[1])]
            # Drone tracks differ: run A took off in task 1, run B stayed on the ground.
            heights = page.evaluate("window.consoleView.players.map(p => Math.max("
                                    "...p.dronesAt(p.t1).map(d => d.z)))")
            assert heights[0] > 5.0 and heights[1] < 1.0
            assert session in (page.text_content("header h1") or "")
            shot(page, "compare-replays")
    finally:
        proc.terminate()
        proc.wait(10)
