"""On an 80-column terminal, the line of a failed task shows its verdict first: the progress
bar's console cuts what does not fit at the end of the line, never the verdict."""

from __future__ import annotations

import io
import re
from pathlib import Path
from typing import Any

import pytest

from benchmark.running.progress import ProgressBar, task_line
from tests.bench_fixtures import small_session, write_json
from tests.test_terminal_output import _in_terminal

ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def _record(**changes: Any) -> dict[str, Any]:
    return {"session": "area_assignment_and_patrol-medium-12", "task": "t06",
            "template": "imported:Patrol the three northern areas", "passed": False,
            "finish": "agent_error", "checks_passed": 0, "checks_total": 3, "tool_calls": 41,
            "sim_time_s": 412.0, "wall_time_s": 3.25, **changes}


def test_a_failed_line_leads_with_its_verdict_in_80_columns(monkeypatch: pytest.MonkeyPatch
                                                             ) -> None:
    monkeypatch.setenv("COLUMNS", "80")
    stream = _Terminal()
    with ProgressBar("tasks", stream=stream) as bar:
        bar.begin(2)
        bar.advance(task_line(_record(), 1), passed=False)
        bar.advance(task_line(_record(passed=True, finish="finished", task="t07"), 2),
                    passed=True)
    lines = [ANSI.sub("", line).rstrip() for line in stream.getvalue().splitlines()]
    (failed,) = [line for line in lines if "t06" in line or "fail" in line]
    assert failed.startswith("    1 fail [agent_error]  0/3  checks  area_assignment_and_"), failed
    assert len(failed) <= 80
    assert task_line(_record(passed=True, finish="finished"), 7).startswith("    7 PASS  0/3 ")


@pytest.mark.mavsdk
@pytest.mark.slow
def test_bench_run_in_an_80_column_terminal(tmp_path: Path) -> None:
    session = write_json(tmp_path / "s.json", small_session(["takeoff_hold", "climb_and_face"]))
    status, text = _in_terminal("bench", "run", "--agent", "noop", "--sessions", str(session),
                                "--out", str(tmp_path / "out"), columns=80)
    assert status == 0, text[-3000:]
    plain = ANSI.sub("", text)  # the bar redraws itself in place: lines run together
    failed = re.findall(r" {4}\d (?:fail|PASS)[^\r\n]*", plain)
    assert len(failed) == 2, plain[-3000:]
    for line in failed:
        assert re.match(r" {4}\d fail  0/\d+\s+checks  area_search", line), line
        assert len(line) <= 80, line
