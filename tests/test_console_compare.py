"""The console's leaderboard and compare view in headless Chromium over three runs served by
`mavswarm replay`: the leaderboard ranks them with their intervals and sorts by any column;
the compare view shows the metric deltas with paired intervals, paired changes by family and
level, and filters the tasks down to those whose verdict differs; bad run ids get a clear
error."""

from __future__ import annotations

import os
import subprocess
from collections.abc import Iterator
from typing import Any

import httpx
import pytest

from tests.browser_fixtures import open_page, shot
from tests.cli_fixtures import MAVSWARM, read_until
from tests.compare_fixtures import write_results
from tests.ports import unused_tcp_port
from tests.test_compare_browser import LEVELS, _suite_records

pytestmark = [pytest.mark.browser]


@pytest.fixture(scope="module")
def served(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    work = tmp_path_factory.mktemp("served")
    for name, agent, skill in (("baseline", "react", 3), ("better", "workflow", 5),
                               ("worse", "noop", 1)):
        write_results(work / name, _suite_records(agent, skill))
    port = unused_tcp_port()
    proc = subprocess.Popen([*MAVSWARM, "replay", str(work / "baseline"), str(work / "better"),
                             str(work / "worse"), "--port", str(port)],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        read_until(proc, "http://", 30)
        yield f"http://127.0.0.1:{port}"
    finally:
        proc.terminate()
        proc.wait(10)


def _column(page: Any, index: int) -> list[str]:
    return page.locator(f"#leaderboard tr td:nth-child({index})").all_text_contents()


def test_leaderboard_ranks_the_runs_with_intervals_and_sorts(browser: Any, served: str) -> None:
    with open_page(browser, f"{served}/leaderboard") as page:
        assert _column(page, 2) == ["better", "baseline", "worse"]  # by task pass rate
        task_pass = _column(page, 5)
        assert task_pass[0].startswith("77.8 % [") and task_pass[2].startswith("11.1 % [")
        assert page.locator("#leaderboard .ci-bar").count() == 9
        page.click("#leaderboard th[data-column='Task Pass']")
        assert _column(page, 2) == ["worse", "baseline", "better"]
        page.click("#leaderboard th[data-column='agent']")
        assert _column(page, 3) == ["noop", "react", "workflow"]
        href = page.locator("#leaderboard tr[data-run='worse'] a", has_text="compare with")
        assert "a=better&b=worse" in (href.get_attribute("href") or "")
        shot(page, "leaderboard")


def test_compare_view_shows_deltas_by_family_and_level_and_filters(browser: Any,
                                                                   served: str) -> None:
    with open_page(browser, f"{served}/compare?a=baseline&b=better") as page:
        summary = page.text_content("#compare-summary") or ""
        assert "A passes 16/36, B passes 28/36; 12 tasks differ" in summary
        assert "12 fail→pass, 0 pass→fail" in summary
        metrics = page.locator("#compare-metrics tr").all_text_contents()
        assert len(metrics) == 4 and "+33.3 pp [" in metrics[1]
        assert page.locator("#compare-family tr").count() == 4  # header + 3 families
        levels = page.locator("#compare-level tr td:first-child").all_text_contents()
        assert levels == list(LEVELS)
        assert page.locator("#compare-table tr").count() == 37
        page.check("#differences-only")
        assert page.locator("#compare-table tr").count() == 13
        assert page.locator("#compare-table tr.differ").count() == 12
        assert "12 of 36 tasks shown" in (page.text_content("#compare-count") or "")
        link = page.locator("#compare-table tr.differ td a").nth(1).get_attribute("href") or ""
        assert "run=better" in link and "agent=workflow" in link
        shot(page, "compare-view")
    bad = httpx.get(f"{served}/api/compare", params={"a": "baseline", "b": "nope"})
    assert bad.status_code == 404 and "'nope'" in bad.json()["detail"]
    same = httpx.get(f"{served}/api/compare", params={"a": "better", "b": "better"})
    assert same.status_code == 400 and "two different runs" in same.json()["detail"]


def test_compare_view_of_few_sessions_warns(browser: Any, served: str) -> None:
    with open_page(browser, f"{served}/compare?a=worse&b=better") as page:
        assert page.locator("p.note").count() >= 1  # only 9 sessions: rough intervals
        assert "B passes 28/36" in (page.text_content("#compare-summary") or "")
