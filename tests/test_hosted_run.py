"""Hosted runs (`mavswarm bench run --agent external`) played by agents in processes of their
own over real sockets: a scripted client over REST and one over MCP (the official SDK's client)
score exactly as the same calls made in-process, whatever they think in between, as do two
clients playing two sessions hosted at once; the run writes its records and reports and exits
0 once `/next` has answered 204."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from benchmark.running.results import read_records
from tests.hosted_fixtures import (
    CLIENT,
    SCRIPT,
    compared,
    in_process_records,
    run_client,
    session_file,
    start_host,
)

pytestmark = [pytest.mark.mavsdk, pytest.mark.slow]


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return session_file(tmp_path_factory.mktemp("hosted"))


@pytest.fixture(scope="module")
def script(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("script") / "script.json"
    path.write_text(json.dumps(SCRIPT))
    return path


@pytest.fixture(scope="module")
def in_process(session: Path) -> list[dict]:
    return in_process_records(session, SCRIPT)


def _hosted(session: Path, script: Path, out: Path, surface: str, *extra: str
            ) -> tuple[list[dict], list[dict]]:
    host = start_host([session], out)
    try:
        client = run_client(surface, host, script, *extra)
        status, printed = host.wait()
    finally:
        host.kill()
    assert client.returncode == 0, client.stderr
    assert status == 0, printed
    assert "2 new task records" in printed and "report:" in printed
    for name in ("report.md", "report.json", "report.html"):
        assert (out / name).exists(), name
    played = [json.loads(line) for line in client.stdout.splitlines()]
    return read_records(out / "results.jsonl"), played


def test_a_rest_client_process_scores_as_the_same_calls_in_process(
        session: Path, script: Path, in_process: list[dict], tmp_path: Path) -> None:
    records, played = _hosted(session, script, tmp_path / "rest", "rest")
    assert [r["key"] for r in records] == ["area_search-easy-1/t01/external/0",
                                           "area_search-easy-1/t02/external/0"]
    assert {r["agent"] for r in records} == {"external"}
    assert compared(records) == compared(in_process)
    assert records[0]["passed"] and records[0]["finish"] == "finished"
    assert [p["task"] for p in played] == ["t01", "t02"]
    assert all(status == 200 for p in played for status, _ in p["results"])
    # The record carries the same fields as an in-process agent's (the replay is kept apart).
    assert set(records[0]) == set(in_process[0]) - {"replay"}
    replays = list((tmp_path / "rest" / "replay").rglob("t0*.external.0.json.gz"))
    assert len(replays) == 2, replays


def test_an_mcp_client_process_thinking_scores_the_same(
        session: Path, script: Path, in_process: list[dict], tmp_path: Path) -> None:
    records, played = _hosted(session, script, tmp_path / "mcp", "mcp", "--think-s", "0.3")
    assert compared(records) == compared(in_process)
    took_off = played[0]["results"][0][1]
    assert took_off["status"] == "ok" and "took off" in took_off["message"]


def test_two_client_processes_play_two_sessions_at_once_as_in_process(
        session: Path, script: Path, in_process: list[dict], tmp_path: Path) -> None:
    twin = session_file(tmp_path, "twin.json", id="twin-session")
    out = tmp_path / "parallel"
    host = start_host([session, twin], out, "--workers", "2")
    try:
        clients = [subprocess.Popen([sys.executable, CLIENT, "rest", host.url, str(script)],
                                    stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                   for _ in range(2)]
        played = [c.communicate(timeout=120) for c in clients]
        status, printed = host.wait()
    finally:
        host.kill()
    assert [c.returncode for c in clients] == [0, 0], played
    assert status == 0, printed
    records = read_records(out / "results.jsonl")
    assert len(records) == len({r["key"] for r in records}) == 4
    for session_id in ("area_search-easy-1", "twin-session"):
        mine = [{**r, "session": "area_search-easy-1"} for r in records
                if r["session"] == session_id]
        assert compared(mine) == compared(in_process), session_id
