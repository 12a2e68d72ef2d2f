"""In headless Chromium: compare.html opened from disk draws its charts and tables with
nothing fetched from anywhere, and each changed task links to its own run's inspector page;
`bench report` of two runs served by `mavswarm replay` keeps them apart, and a task link of
the second run opens the second run's page (not the first run's, as a link without the run
did)."""

from __future__ import annotations

import os
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from benchmark.reporting.compare import compare_paths, write_compare
from tests.browser_fixtures import open_page, shot
from tests.cli_fixtures import MAVSWARM, read_until
from tests.compare_fixtures import record, write_results
from tests.ports import unused_tcp_port

pytestmark = [pytest.mark.browser]

FAMILIES = ("area_search", "target_tracking", "formation")
LEVELS = ("easy", "moderate", "hard")


def _suite_records(agent: str, skill: int) -> list[dict[str, Any]]:
    """Nine sessions (3 families x 3 levels) of four tasks; the agent passes a task when its
    skill beats the task's difficulty number."""
    rows = []
    for f, family in enumerate(FAMILIES):
        for lv, level in enumerate(LEVELS):
            for k in range(4):
                hardness = lv * 2 + (k + f) % 3
                rows.append(record(f"{family}-{level}-1", f"t{k:02d}", agent,
                                   skill > hardness, family=family, level=level,
                                   category=("navigation", "photo")[k % 2],
                                   template=f"tpl{k}", checks_passed=1 if k == 3 else None))
    return rows


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    work = tmp_path_factory.mktemp("compare")
    return [write_results(work / name, _suite_records(agent, skill))
            for name, agent, skill in (("baseline", "react", 3), ("better", "workflow", 5),
                                       ("worse", "noop", 1))]


def test_compare_html_renders_from_disk(browser: Any, runs: list[Path], tmp_path: Path) -> None:
    report = compare_paths(runs)
    _, _, html_path = write_compare(report, tmp_path, inspector_url="http://inspector.test:1")
    requests: list[str] = []
    page = browser.new_page(viewport={"width": 1300, "height": 900})
    page.on("request", lambda request: requests.append(request.url))
    try:
        page.goto(html_path.as_uri())
        charts = page.evaluate("""() => Object.fromEntries([...document.querySelectorAll(
            "section.panel[id]")].map(panel => [panel.id, [...panel.querySelectorAll(
            "svg.chart")].map(svg => { const box = svg.getBoundingClientRect();
              const marks = [...svg.querySelectorAll("rect, circle, polyline")].filter(m => {
                const b = m.getBoundingClientRect(); return b.width > 0 || b.height > 0; });
              return {width: box.width, height: box.height, marks: marks.length}; })]))""")
        for ident in ("intervals", "transitions", "difficulty", "families"):
            assert charts[ident], ident
            for chart in charts[ident]:
                assert chart["width"] > 300 and chart["height"] > 60 and chart["marks"] > 0, \
                    (ident, chart)
        # One diverging row per run against the baseline; one family chart per pair.
        assert page.locator("#transitions g.change").count() == 2
        assert len(charts["families"]) == 2
        gained = page.evaluate("""() => [...document.querySelectorAll(
            "#transitions rect.gained")].map(r => r.getBoundingClientRect().width)""")
        lost = page.evaluate("""() => [...document.querySelectorAll(
            "#transitions rect.lost")].map(r => r.getBoundingClientRect().width)""")
        better, worse = report.pairs
        assert (better.overall.pass_to_fail, worse.overall.fail_to_pass) == (0, 0)
        assert gained[0] > 20 and lost[0] == 0 and gained[1] == 0 and lost[1] > 20
        # A line per run over the levels, in difficulty order.
        assert page.locator("#difficulty polyline").count() == 3
        assert page.locator("#difficulty svg text").all_text_contents()[5:8] == list(LEVELS)
        assert page.locator("#category-table tbody tr").count() == 2
        assert page.locator("#endpoint-table tbody tr").count() == 2
        assert page.locator("#level-table tbody tr").first.text_content().startswith("easy")
        # Changed tasks link each run's own inspector page.
        hrefs = page.evaluate("""() => [...document.querySelectorAll("#changed a")]
            .map(a => a.getAttribute("href"))""")
        changed = len(better.changed) + len(worse.changed)
        assert len(hrefs) == 2 * changed and changed > 0
        assert any("run=better&agent=workflow&trial=0" in h for h in hrefs)
        assert any("run=baseline&agent=react&trial=0" in h for h in hrefs)
        assert all(h.startswith("http://inspector.test:1/inspect/") for h in hrefs)
        shot(page, "compare-html")
    finally:
        page.close()
    assert requests and all(url.startswith("file://") for url in requests), requests


@pytest.fixture()
def served(runs: list[Path]) -> Iterator[str]:
    port = unused_tcp_port()
    proc = subprocess.Popen([*MAVSWARM, "replay", str(runs[0]), str(runs[1]), "--port",
                             str(port)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        read_until(proc, "http://", 30)
        yield f"http://127.0.0.1:{port}"
    finally:
        proc.terminate()
        proc.wait(10)


def test_report_of_two_runs_links_each_task_to_its_own_run(
        browser: Any, runs: list[Path], served: str, tmp_path: Path) -> None:
    out = tmp_path / "rep"
    done = subprocess.run([*MAVSWARM, "bench", "report", str(runs[0] / "results.jsonl"),
                           str(runs[1]), "--out", str(out), "--inspector-url", served],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "baseline (" in done.stdout and "better (" in done.stdout
    with open_page(browser, (out / "report.html").as_uri(), ready=False) as page:
        rows = page.locator("#runs-table tbody tr")
        assert rows.count() == 2
        assert "react" in rows.nth(0).text_content() and "workflow" in rows.nth(1).text_content()
        assert "41.7 %" in rows.nth(0).text_content()  # 15 / 36, its own rate, not pooled
        page.click("#runs-table a >> text=better")
        page.wait_for_url("**/report-better.html")
        link = page.locator("#tasks a").first.get_attribute("href")
    assert link.startswith(f"{served}/inspect/") and "run=better&agent=workflow" in link
    with open_page(browser, link) as page:
        assert page.evaluate("window.consoleView.record.agent") == "workflow"
        shot(page, "report-link-second-run")
    # The link without its run opens whichever run the server lists first: the wrong one.
    with open_page(browser, link.split("?")[0] + "?trial=0") as page:
        assert page.evaluate("window.consoleView.record.agent") == "react"
