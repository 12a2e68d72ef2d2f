"""`mavswarm replay` in headless Chromium: a ground-truth file scrubbed on its timeline puts the
drones where the truth had them; a benchmark run's task page shows its window, the agent's
tool calls and the check tree with a failed check's measured value (the unsearched area shaded);
runs filter and compare task by task; results written before replays were kept still open,
with a note."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import httpx
import pytest

from emulator.clock import ClockConfig
from emulator.scenario import default_scenario
from emulator.swarm import PortPlan, Swarm
from emulator.truth import TruthLog
from tests.browser_fixtures import (
    LoopThread,
    drone_pixels_near,
    map_view,
    open_page,
    screen_of,
    shot,
    webgl_colours,
)
from tests.cli_fixtures import MAVSWARM, ROOT, read_until, run_in_process_thread
from tests.ports import unused_tcp_port, unused_udp_port

pytestmark = [pytest.mark.browser, pytest.mark.mavsdk]

SESSION = "area_search-easy-1-mini"


async def _fly(path: Path) -> None:
    base = default_scenario(2)
    spots = [(0.0, 0.0), (40.0, 0.0)]
    vehicles = tuple(replace(v, position_m=(x, y, 0.0), home_m=(x, y, 0.0))
                     for v, (x, y) in zip(base.vehicles, spots, strict=True))
    ports = PortPlan(bind_host="127.0.0.1", bind_port=unused_udp_port(), api_port=0, gcs_port=0)
    async with Swarm(replace(base, vehicles=vehicles), clock=ClockConfig(stepped=True),
                     ports=ports) as swarm:
        one, two = swarm.fleet.autopilots
        for ap in (one, two):
            ap.arm()
            ap.takeoff(15.0)
        await swarm.wait_idle()
        one.reposition((150.0, 120.0, 15.0))
        two.reposition((-80.0, 160.0, 25.0))
        await swarm.wait_idle()
        await swarm.advance(2.0)
        swarm.export_truth(path)


def _serve(*args: str, cwd: Path | None = None) -> tuple[subprocess.Popen[str], str]:
    port = unused_tcp_port()
    proc = subprocess.Popen([*MAVSWARM, "replay", *args, "--port", str(port)], cwd=cwd,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env={**os.environ, "PYTHONUNBUFFERED": "1"})
    read_until(proc, "http://", 30)
    return proc, f"http://127.0.0.1:{port}"


def _stop(proc: subprocess.Popen[str]) -> None:
    proc.terminate()
    proc.wait(10)


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    """A truth file of two drones' flights, and two benchmark runs (oracle, noop) of a
    two-task session, plus the noop run's results as written before replays were kept."""
    work = tmp_path_factory.mktemp("recorded")
    truth = work / "flight.truth.npz"
    loop = LoopThread()  # the browser's Playwright already runs a loop in this thread
    try:
        loop.run(_fly(truth))
    finally:
        loop.close()
    source = json.loads((ROOT / "benchmark/sessions/area_search-easy-1.json").read_text())
    source["tasks"], source["id"] = [source["tasks"][0], source["tasks"][2]], SESSION
    session = work / "mini.json"
    session.write_text(json.dumps(source))
    # The runs are only what the pages show: `bench run`'s main in this process (on a thread
    # of its own: Playwright's loop runs in this one), not two more interpreters to start.
    for agent, out in (("oracle", "runA"), ("noop", "runB")):
        done = run_in_process_thread("bench", "run", "--agent", agent, "--sessions",
                                     str(session), "--out", str(work / out), cwd=work)
        assert done.returncode == 0, (done.stdout[-2000:], done.stderr[-2000:])
    (work / "old").mkdir()
    shutil.copy(work / "runB" / "results.jsonl", work / "old" / "results.jsonl")
    runs, url = _serve(str(work / "runA"), str(work / "runB"), str(work / "old"))
    replay, truth_url = _serve(str(truth))
    try:
        yield {"work": work, "truth": truth, "runs": url, "replay": truth_url}
    finally:
        _stop(runs)
        _stop(replay)


def test_scrubbing_a_truth_file_moves_the_drones_to_the_truth(browser: Any,
                                                              recorded: dict[str, Any]) -> None:
    log = TruthLog.load(recorded["truth"])
    with open_page(browser, f"{recorded['replay']}/replay") as page:
        t0, t1 = page.evaluate("[window.consoleView.player.t0, window.consoleView.player.t1]")
        assert t0 == pytest.approx(0.0, abs=0.05) and t1 == pytest.approx(log.end_t_s, abs=0.05)
        seen = []
        for slider in ("350", "700"):
            page.locator("#replay-slider").fill(slider)
            t = page.evaluate("window.consoleView.player.t")
            assert t == pytest.approx(t0 + (t1 - t0) * int(slider) / 1000, abs=0.05)
            for drone in ("d1", "d2"):
                x, y, _ = log.position_at(drone, t)
                assert drone_pixels_near(page, x, y) >= 8, f"{drone} at t={t:.1f}: ({x}, {y})"
            seen.append(log.position_at("d1", t))
        assert abs(seen[1][0] - seen[0][0]) + abs(seen[1][1] - seen[0][1]) > 30
        assert webgl_colours(page) >= 20
        page.click("#replay-play")
        before = page.evaluate("window.consoleView.player.t")
        page.wait_for_timeout(800)
        assert page.evaluate("window.consoleView.player.t") > before
        page.click("#replay-play")
        shot(page, "replay-truth")


def test_the_inspector_explains_a_failed_check(browser: Any, recorded: dict[str, Any]) -> None:
    url = f"{recorded['runs']}/inspect/{SESSION}/t03?trial=0&run=runB"
    with open_page(browser, url) as page:
        assert page.text_content("#verdict") == "FAIL"
        failed = page.locator("#check-tree li.leaf.fail").all_text_contents()
        area = next(text for text in failed if "searched area percentage" in text)
        assert "of t1: 0 < 0.85" in area
        assert "Sweep Search Area 1" in (page.text_content("#task-text") or "")
        world = json.loads((recorded["work"] / "mini.json").read_text())
        t1 = next(t for t in world["targets"] if t["id"] == "t1")["position"]
        sx, sy = screen_of(map_view(page), t1["x"], t1["y"])
        red, green = page.evaluate("""([x, y]) => { const m = window.consoleView.map; m.draw();
            const p = m.ctx.getImageData(Math.round(x * m.dpr), Math.round(y * m.dpr), 1, 1).data;
            return [p[0], p[1]]; }""", [sx, sy])
        assert red > green + 60, "the unsearched area is not shaded"
        shot(page, "inspector-failed")


def test_a_task_page_lays_the_tool_calls_on_the_replay(browser: Any,
                                                       recorded: dict[str, Any]) -> None:
    record = json.loads((recorded["work"] / "runA" / "results.jsonl").read_text()
                        .splitlines()[1])
    with open_page(browser, f"{recorded['runs']}/inspect/{SESSION}/t03?trial=0") as page:
        assert page.text_content("#verdict") == "PASS"
        calls = page.locator("#call-list li").all_text_contents()
        assert len([c for c in calls if " finish(" not in c]) == record["tool_calls"]
        assert any(" finish(" in c for c in calls)  # logged, though it costs no budget
        assert any("take_off(altitude_m=25) → ok" in c for c in calls)
        t0, t1 = page.evaluate("[window.consoleView.player.t0, window.consoleView.player.t1]")
        assert [t0, t1] == pytest.approx(record["window_s"], abs=0.01)
        page.locator("#call-list li").nth(4).click()
        clicked = page.evaluate("window.consoleView.player.calls[4].t0_s")
        assert page.evaluate("window.consoleView.player.t") == pytest.approx(clicked)
        assert webgl_colours(page) >= 20
        shot(page, "inspector-passed")


def test_runs_filter_and_compare_and_old_results_open_with_a_note(
        browser: Any, recorded: dict[str, Any]) -> None:
    base = recorded["runs"]
    with open_page(browser, f"{base}/runs/runB") as page:
        assert page.locator("#task-table tr.fail").count() == 2
        page.select_option("#filter-endpoint", "drone_has_taken_photo")
        assert page.locator("#task-table tr.fail").count() == 2
        page.select_option("#filter-template", "photo_at_point")
        assert page.locator("#task-table tr.fail").count() == 1
        assert "1 of 2 tasks" in (page.text_content("#task-count") or "")
        shot(page, "runs")
    with open_page(browser, f"{base}/compare") as page:
        summary = page.text_content("#compare-summary") or ""
        assert "A passes 2/2" in summary and "B passes 0/2" in summary
        assert "2 tasks differ" in summary
        shot(page, "compare")
    with open_page(browser, f"{base}/inspect/{SESSION}/t01?trial=0&run=old") as page:
        assert "no replay was recorded" in (page.text_content("#replay-note") or "")
        assert page.locator("#check-tree li.leaf.fail").count() == 2
    missing = httpx.get(f"{base}/api/task/{SESSION}/t99?trial=0")
    assert missing.status_code == 404 and "t99" in missing.json()["detail"]
