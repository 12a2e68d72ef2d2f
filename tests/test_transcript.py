"""An LLM agent's transcript: the ReAct agent on a scripted model, run by `bench run`, stores
every message with its simulated time, the tool calls with their arguments in full (the tool
log cuts them) and the tokens of each turn beside the task's replay; the run inspector in
headless Chromium lists it on the task's timeline, a click on a message moves the replay to
its time, and the page header links runs, compare, leaderboard and editor."""

from __future__ import annotations

import json
import os
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from agent_contract.budget import (
    TRANSCRIPT_MAX_CHARS,
    TRANSCRIPT_MAX_ENTRIES,
    TRANSCRIPT_MAX_TEXT,
    BudgetedTools,
)
from agent_contract.protocol import AgentTask, TaskBudget
from benchmark.running.replay_data import read_json_gz, replay_path
from tests.bench_fixtures import small_session, write_json
from tests.browser_fixtures import ARTIFACTS, open_page, shot
from tests.cli_fixtures import MAVSWARM, ROOT, read_until, run_in_process_thread
from tests.ports import unused_tcp_port
from tests.scripted_llm import call, scripted_llm

SUMMARY = "climbed and held; " + "the long account of it goes on " * 20  # > 200 characters


class _Clock:
    """Simulated time for the accounting alone (no swarm: the bounds are plain bookkeeping)."""

    def __init__(self) -> None:
        self.t_s = 12.5

    def clock_s(self) -> float:
        return self.t_s


class _Gateway:
    def __init__(self) -> None:
        self.services = _Clock()
        self.drones: dict[str, Any] = {}


def test_add_transcript_records_the_time_and_is_bounded() -> None:
    tools = BudgetedTools(_Gateway(), AgentTask("s", "t", "x", TaskBudget(10, 100.0)))  # type: ignore[arg-type]
    tools.add_transcript("assistant", "go", tool_calls=[{"id": "c1", "name": "take_off",
                                                          "arguments": {"drone_id": "d1"}}],
                         tokens={"prompt": 7, "completion": 3})
    assert tools.transcript == [{"t_s": 12.5, "role": "assistant", "content": "go",
                                 "tool_calls": [{"id": "c1", "name": "take_off",
                                                 "arguments": '{"drone_id": "d1"}'}],
                                 "tokens": {"prompt": 7, "completion": 3}}]
    with pytest.raises(ValueError, match="transcript role must be one of"):
        tools.add_transcript("robot", "hi")
    with pytest.raises(ValueError, match="each transcript tool call must be an object"):
        tools.add_transcript("assistant", "x", tool_calls=["take_off(d1)"])  # type: ignore[list-item]
    with pytest.raises(ValueError, match="transcript tokens must be"):
        tools.add_transcript("assistant", "x", tokens={"prompt": -1, "completion": 2})
    with pytest.raises(ValueError, match="transcript tokens must be"):
        tools.add_transcript("assistant", "x", tokens={"prompt": "many"})  # type: ignore[dict-item]
    assert len(tools.transcript) == 1
    tools.add_transcript("tool", "y" * (TRANSCRIPT_MAX_TEXT + 50), tool_call_id="c1")
    assert tools.transcript[1]["content"] == "y" * TRANSCRIPT_MAX_TEXT + "..."
    assert tools.transcript[1]["tool_call_id"] == "c1"
    for _ in range(TRANSCRIPT_MAX_CHARS // TRANSCRIPT_MAX_TEXT + 10):
        tools.add_transcript("user", "z" * TRANSCRIPT_MAX_TEXT)
    kept = sum(len(e["content"]) for e in tools.transcript)
    assert kept <= TRANSCRIPT_MAX_CHARS and tools.transcript_dropped >= 10
    for _ in range(TRANSCRIPT_MAX_ENTRIES + 5):
        tools.add_transcript("user", "")
    assert len(tools.transcript) == TRANSCRIPT_MAX_ENTRIES


def _script(drone: str, altitude_m: float) -> list[Any]:
    return [
        {"role": "assistant", "content": "First I launch the drone.",
         "tool_calls": [call("take_off", {"drone_id": drone, "altitude_m": altitude_m}, "c1")]},
        [call("hover", {"drone_id": drone, "duration_s": 4}, "c2")],
        [call("finish", {"summary": SUMMARY}, "c3")],
    ]


@pytest.fixture(scope="module")
def react_run(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    """`bench run --agent react` on one smoke task against the scripted model, served by
    `mavswarm replay`."""
    work = tmp_path_factory.mktemp("transcript")
    data = small_session(["takeoff_hold"])
    op = data["tasks"][0]["oracle"][0][0]
    session = write_json(work / "s.json", data)
    with scripted_llm(_script(op["drone"], op["altitude_m"])) as llm:
        run = run_in_process_thread(
            "bench", "run", "--agent", "react", "--model", "scripted", "--base-url",
            llm.base_url, "--sessions", str(session), "--out", str(work / "react"), cwd=ROOT)
    assert run.returncode == 0, run.stderr[-2000:]
    record = json.loads((work / "react" / "results.jsonl").read_text())
    port = unused_tcp_port()
    proc = subprocess.Popen([*MAVSWARM, "replay", str(work / "react"), "--port", str(port)],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        read_until(proc, "http://", 30)
        yield {"record": record, "out": work / "react", "url": f"http://127.0.0.1:{port}",
               "drone": op["drone"]}
    finally:
        proc.terminate()
        proc.wait(10)


def _replay(run: dict[str, Any]) -> dict[str, Any]:
    record = run["record"]
    path = replay_path(Path(run["out"]), record["session"], record["task"], record["agent"],
                       record["trial"])
    data: dict[str, Any] = read_json_gz(path)
    return data


@pytest.mark.mavsdk
def test_the_react_transcript_is_stored_beside_the_replay(react_run: dict[str, Any]) -> None:
    record, replay = react_run["record"], _replay(react_run)
    assert record["passed"] and "transcript" not in record
    transcript = replay["transcript"]
    assert replay["transcript_dropped"] == 0
    assert [e["role"] for e in transcript] == [
        "system", "user", "assistant", "tool", "assistant", "tool", "assistant", "tool"]
    answers = [e for e in transcript if e["role"] == "assistant"]
    assert all(e["tokens"] == {"prompt": 100, "completion": 20} for e in answers)
    assert answers[0]["content"] == "First I launch the drone."
    finish = answers[2]["tool_calls"][0]
    assert finish["name"] == "finish" and finish["id"] == "c3"
    assert json.loads(finish["arguments"]) == {"summary": SUMMARY}  # in full
    logged = next(c for c in replay["calls"] if c["name"] == "finish")
    assert logged["args"]["summary"] == SUMMARY[:200] + "..."  # the tool log cuts it
    assert [e["tool_call_id"] for e in transcript if e["role"] == "tool"] == ["c1", "c2", "c3"]
    times = [e["t_s"] for e in transcript]
    assert times == sorted(times)
    assert replay["t0_s"] <= times[0] and times[-1] <= replay["t1_s"]
    # The hover answer comes after the climb, the finish after the 4 s hover.
    assert answers[1]["t_s"] > answers[0]["t_s"] and answers[2]["t_s"] >= answers[1]["t_s"] + 4


@pytest.mark.browser
@pytest.mark.mavsdk
def test_the_inspector_shows_the_transcript_on_the_timeline(
        browser: Any, react_run: dict[str, Any]) -> None:
    record = react_run["record"]
    url = f"{react_run['url']}/inspect/{record['session']}/{record['task']}?trial=0"
    with open_page(browser, url) as page:
        entries = page.locator("#transcript li.entry")
        assert entries.count() == 8
        assert "First I launch the drone." in (entries.nth(2).text_content() or "")
        finish = entries.nth(6).text_content() or ""
        assert SUMMARY.strip() in finish and "100 + 20 tokens" in finish
        assert "take_off" in (entries.nth(2).text_content() or "")
        times = page.evaluate("window.consoleView.player.transcript.map((e) => e.t_s)")
        page.locator("#transcript li.entry").nth(4).click()
        assert page.evaluate("window.consoleView.player.t") == pytest.approx(times[4])
        page.locator("#transcript li.entry").nth(7).click()
        assert page.evaluate("window.consoleView.player.t") == pytest.approx(times[7])
        assert "current" in (entries.nth(7).get_attribute("class") or "")
        nav = page.locator("header nav a").all_text_contents()
        assert nav == ["runs", "compare", "leaderboard", "editor"]
        shot(page, "inspector-transcript")
        page.screenshot(path=str(ARTIFACTS / "inspector-transcript-page.png"), full_page=True)
        page.click("header nav a:text-is('leaderboard')")
        page.wait_for_selector("body[data-ready='1']")
        assert page.text_content("h1") == "Leaderboard"
        assert record["agent"] in (page.text_content("table") or "")
    with open_page(browser, f"{react_run['url']}/runs") as page:
        assert page.locator("header nav a").all_text_contents() == nav
        assert page.get_attribute("header nav a.current", "href", timeout=2000) is not None

