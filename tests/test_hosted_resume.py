"""A hosted run killed with SIGKILL mid-task resumes from its results file: the same command
offers only the tasks not recorded, and the records equal an uninterrupted in-process run's.
With `--workers 2`, two sessions are hosted at once: each `/next` hands out another task, a
third one answers 409, and every task is recorded once."""

from __future__ import annotations

import json
import signal
import time
from pathlib import Path
from typing import Any

import httpx
import pytest

from benchmark.running.hosted.endpoint import MAX_WAIT_S
from benchmark.running.results import read_records
from tests.hosted_fixtures import SCRIPT, compared, in_process_records, session_file, start_host

pytestmark = [pytest.mark.mavsdk, pytest.mark.slow]


def _play(http: httpx.Client, offer: dict[str, Any], calls: list[list[Any]]) -> None:
    for name, arguments in calls:
        r = http.post(f"{offer['tools_url']}/{name}", json=arguments,
                      headers={"X-API-Key": offer["key"]})
        assert r.status_code == 200, r.text


def _next(http: httpx.Client, url: str) -> httpx.Response:
    """`/next`, waiting as long as the endpoint allows for a task to be offered (a loaded
    machine can take longer than its default wait to start a session's worker)."""
    return http.get(f"{url}/next", params={"wait_s": MAX_WAIT_S})


def _lines(path: Path, count: int, timeout_s: float = 30.0) -> list[str]:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        lines = path.read_text().splitlines() if path.exists() else []
        if len(lines) >= count:
            return lines
        time.sleep(0.05)
    raise AssertionError(f"{path} did not reach {count} line(s)")


def test_a_host_killed_mid_task_resumes_without_loss_or_duplicate(tmp_path: Path) -> None:
    session = session_file(tmp_path)
    out = tmp_path / "out"
    host = start_host([session], out)
    try:
        with httpx.Client(timeout=MAX_WAIT_S + 60.0) as http:
            first = _next(http, host.url).json()
            _play(http, first, SCRIPT["t01"])
            before = _lines(out / "results.jsonl", 1)
            second = _next(http, host.url).json()
            assert second["task_id"] == "t02"
            _play(http, second, SCRIPT["t02"][:1])  # mid-task
            host.proc.send_signal(signal.SIGKILL)
            host.proc.wait(timeout=10)
    finally:
        host.kill()
    assert (out / "results.jsonl").read_text().splitlines() == before

    again = start_host([session], out)
    try:
        with httpx.Client(timeout=MAX_WAIT_S + 60.0) as http:
            resumed = _next(http, again.url).json()
            assert resumed["task_id"] == "t02" and resumed["key"] != second["key"]
            _play(http, resumed, SCRIPT["t02"])
            assert _next(http, again.url).status_code == 204
        status, printed = again.wait()
    finally:
        again.kill()
    assert status == 0, printed
    lines = (out / "results.jsonl").read_text().splitlines()
    assert lines[0] == before[0] and len(lines) == 2
    # What was done and judged equals an uninterrupted run's; only the window's place on the
    # clock moves (a resumed session's clock starts again at 0, as for any agent).
    resumed_run = compared(read_records(out / "results.jsonl"))
    whole_run = compared(in_process_records(session, SCRIPT))
    for record in resumed_run[1:] + whole_run[1:]:
        start, end = record.pop("window_s")
        record["window_length_s"] = round(end - start, 3)
    assert resumed_run == whole_run


def test_two_sessions_hosted_at_once(tmp_path: Path) -> None:
    one = session_file(tmp_path, "one.json")
    two = session_file(tmp_path, "two.json", id="twin-session")
    host = start_host([one, two], tmp_path / "out", "--workers", "2")
    assert len(host.seats) == 2
    try:
        with httpx.Client(timeout=MAX_WAIT_S + 60.0) as http:
            a, b = (_next(http, host.url).json() for _ in range(2))
            assert {a["session"], b["session"]} == {"area_search-easy-1", "twin-session"}
            assert a["base_url"] != b["base_url"]
            r = _next(http, host.url)
            assert r.status_code == 409 and "2 session(s) at once" in r.json()["detail"]
            taken = [a, b]
            while taken:
                offer = taken.pop()
                _play(http, offer, [["finish", {}]])
                r = _next(http, host.url)
                if r.status_code == 200:
                    taken.append(r.json())
                else:
                    assert r.status_code == 204 or (r.status_code == 409 and taken), r.text
            status = http.get(f"{host.url}/status").json()
        code, printed = host.wait()
    finally:
        host.kill()
    assert code == 0, printed
    assert status["handed_out"] == 4
    records = read_records(tmp_path / "out" / "results.jsonl")
    assert sorted(r["key"] for r in records) == sorted(
        f"{s}/{t}/external/0" for s in ("area_search-easy-1", "twin-session")
        for t in ("t01", "t02"))
    assert all(r["finish"] == "finished" for r in records)
    json.dumps(records)


def _children(pid: int) -> set[int]:
    found: set[int] = set()
    for task in Path(f"/proc/{pid}/task").iterdir():
        found |= {int(c) for c in (task / "children").read_text().split()}
    return found


def test_worker_processes_of_a_killed_host_exit(tmp_path: Path) -> None:
    one = session_file(tmp_path, "one.json")
    two = session_file(tmp_path, "two.json", id="twin-session")
    host = start_host([one, two], tmp_path / "out", "--workers", "2")
    try:
        deadline = time.monotonic() + 60
        while httpx.get(f"{host.url}/status").json()["on_offer"] < 2:
            assert time.monotonic() < deadline, "the two sessions never offered a task"
            time.sleep(0.1)
        workers = _children(host.proc.pid)
        assert len(workers) >= 2
        host.proc.send_signal(signal.SIGKILL)
        host.proc.wait(timeout=10)
        deadline = time.monotonic() + 20
        while any(Path(f"/proc/{pid}").exists() for pid in workers):
            assert time.monotonic() < deadline, "orphaned hosted sessions kept running"
            time.sleep(0.1)
    finally:
        host.kill()
