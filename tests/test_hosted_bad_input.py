"""A hosted run under garbage from its agents: bad `/next` queries, a `/next` while the one
task hosted is out, missing, unknown and stale keys, calls after `finish`, unknown tools and
sessions, malformed and 1 MiB bodies, hundreds of concurrent requests. Each gets a clear 4xx
and changes nothing; the run still records every task exactly once and exits 0. A connection
left idle longer than HTTP clients keep theirs is still answered on (the client closes first,
so a reused connection is never reset under a request)."""

from __future__ import annotations

import asyncio
import socket
import time
from pathlib import Path
from typing import Any

import h11
import httpx
import pytest

from benchmark.running.results import read_records
from llm_tools.input_limits import MAX_BODY_BYTES
from tests.cli_fixtures import run_in_process
from tests.hosted_fixtures import session_file, start_host

pytestmark = [pytest.mark.mavsdk, pytest.mark.slow]

BIG = b'{"x": "' + b"y" * MAX_BODY_BYTES + b'"}'


def _detail(r: httpx.Response) -> str:
    return str(r.json()["detail"])


async def _calls_counted(http: httpx.AsyncClient, offer: dict[str, Any]) -> int:
    r = await http.get(f"{offer['base_url']}/sessions/current/task-progress",
                       headers={"X-API-Key": offer["key"]})
    assert r.status_code == 200, r.text
    return int(r.json()["details"]["tool_calls"])


async def _endpoint_refusals(http: httpx.AsyncClient, url: str) -> None:
    for query in ({"wait_s": "-1"}, {"wait_s": "soon"}, {"wait_s": "1e9"}):
        r = await http.get(f"{url}/next", params=query)
        assert r.status_code == 422, (query, r.text)
    r = await http.post(f"{url}/next", json={})
    assert r.status_code == 405 and "GET" in _detail(r)
    r = await http.post(f"{url}/sessions/current/tasks/next", content=BIG)
    assert r.status_code == 413 and "limit" in _detail(r)
    for headers in ({}, {"X-API-Key": "seat-forged"}):
        r = await http.get(f"{url}/drones", headers=headers)
        assert r.status_code == 401 and "seat" in _detail(r), r.text


async def _task_refusals(http: httpx.AsyncClient, offer: dict[str, Any]) -> None:
    tools, key = offer["tools_url"], {"X-API-Key": offer["key"]}
    refused = [
        (await http.post(f"{tools}/list_drones"), 401, "missing API key"),
        (await http.post(f"{tools}/list_drones", headers={"X-API-Key": "forged"}), 401,
         "unknown API key"),
        (await http.post(f"{tools}/teleport", headers=key, json={}), 404, "unknown tool"),
        (await http.post(f"{tools}/take_off", headers=key, content=b"{"), 422, "JSON"),
        (await http.post(f"{tools}/take_off", headers=key, json={"drone_id": "d1"}), 422,
         "altitude_m"),
        (await http.post(f"{tools}/take_off", headers=key, content=BIG), 413, "limit"),
        (await http.post(f"{offer['base_url']}/sessions/other/tools/list_drones",
                         headers=key), 403, "bound to session"),
        (await http.get(f"{offer['base_url']}/check/sessions/{offer['session']}/task",
                        headers=key), 403, "role"),
        (await http.post(f"{offer['base_url']}/sessions/current/tasks/t99/mark-done",
                         headers=key), 404, "not this key's task"),
    ]
    for r, status, words in refused:
        assert r.status_code == status and words in r.text, (r.status_code, r.text)
    seen = (await http.get(f"{offer['base_url']}/sessions/{offer['session']}",
                           headers=key)).json()
    assert not {"targets", "obstacles", "tasks", "data"} & set(seen)
    assert "checks" not in str(seen) and "oracle" not in str(seen)


async def _answered_after_idling(url: str, path: str, key: str, idle_s: float) -> list[int]:
    """The statuses of two GETs of `path` on one connection, `idle_s` apart."""
    parts = httpx.URL(url)
    reader, writer = await asyncio.open_connection(parts.host, parts.port)
    conn, statuses = h11.Connection(h11.CLIENT), []
    try:
        for pause_s in (0.0, idle_s):
            await asyncio.sleep(pause_s)
            writer.write(conn.send(h11.Request(method="GET", target=path, headers=[
                ("Host", parts.host), ("X-API-Key", key)])) + conn.send(h11.EndOfMessage()))
            await writer.drain()
            while not isinstance(event := conn.next_event(), h11.EndOfMessage):
                if event is h11.NEED_DATA:
                    conn.receive_data(await reader.read(65536))
                elif isinstance(event, h11.Response):
                    statuses.append(event.status_code)
            conn.start_next_cycle()
    finally:
        writer.close()
    return statuses


async def test_garbage_gets_clear_4xx_and_changes_nothing(tmp_path: Path) -> None:
    session = session_file(tmp_path)
    host = start_host([session], tmp_path / "out")
    try:
        limits = httpx.Limits(max_connections=500)
        async with httpx.AsyncClient(timeout=60.0, limits=limits) as http:
            await _endpoint_refusals(http, host.url)
            first = (await http.get(f"{host.url}/next")).json()
            assert first["task_id"] == "t01" and set(first["drones"]) == {"d1", "d2", "d3"}
            idler = asyncio.create_task(_answered_after_idling(
                first["base_url"], "/sessions/current/task-progress", first["key"], 5.5))
            r = await http.get(f"{host.url}/next")  # one session hosted, its task is out
            assert r.status_code == 409 and "t01" in _detail(r) and "finish" in _detail(r)
            await _task_refusals(http, first)
            assert await _calls_counted(http, first) == 0  # nothing above was a call

            # Hundreds at once: exactly the budget's worth of calls runs, the rest are refused.
            budget = first["budget"]["tool_calls"]
            good = [http.post(f"{first['tools_url']}/list_drones",
                              headers={"X-API-Key": first["key"]}) for _ in range(300)]
            bad = [http.post(f"{first['tools_url']}/list_drones",
                             headers={"X-API-Key": f"forged-{k}"}) for k in range(100)]
            answers = await asyncio.gather(*good, *bad)
            statuses = [r.status_code for r in answers[:300]]
            assert statuses.count(200) == budget, sorted(set(statuses))
            assert set(statuses) <= {200, 409, 410}
            assert {r.status_code for r in answers[300:]} == {401}
            after = await http.post(f"{first['tools_url']}/finish",
                                    headers={"X-API-Key": first["key"]}, json={})
            assert after.status_code == 410 and "has ended" in _detail(after)

            # Idle past the clients' 5 s, the same connection still answers (410 once the task
            # has ended), rather than being closed by the server.
            first_status, later_status = await idler
            assert first_status == 200 and later_status in (200, 410)

            second = (await http.get(f"{host.url}/next")).json()
            assert second["task_id"] == "t02" and second["key"] != first["key"]
            stale = await http.post(f"{second['tools_url']}/list_drones",
                                    headers={"X-API-Key": first["key"]})
            assert stale.status_code == 410 and "t01" in _detail(stale)  # the ended task's key
            key = {"X-API-Key": second["key"]}
            done = await http.post(f"{second['tools_url']}/finish", headers=key, json={})
            assert done.status_code == 200 and done.json()["status"] == "ok"
            again = await http.post(f"{second['tools_url']}/finish", headers=key, json={})
            assert again.status_code == 410
            started = time.monotonic()
            assert (await http.get(f"{host.url}/next")).status_code == 204
            assert time.monotonic() - started < 30
        status, printed = host.wait()
    finally:
        host.kill()
    assert status == 0, printed
    records = read_records(tmp_path / "out" / "results.jsonl")
    assert [r["task"] for r in records] == ["t01", "t02"]
    assert len({r["key"] for r in records}) == 2
    assert records[0]["finish"] == "tool_call_budget" and records[0]["tool_calls"] == budget
    assert records[1]["finish"] == "finished" and records[1]["tool_calls"] == 0


def test_a_port_in_use_or_out_of_range_stops_before_anything_runs(tmp_path: Path) -> None:
    session = session_file(tmp_path)
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        for bad, words in ((str(port), "cannot listen on 127.0.0.1"), ("70000", "0 to 65535")):
            run = run_in_process("bench", "run", "--agent", "external", "--sessions",
                                 str(session), "--out", str(tmp_path / "out"), "--port", bad,
                                 cwd=tmp_path)
            assert run.returncode == 2 and words in run.stderr, (run.stdout, run.stderr)
    assert not (tmp_path / "out" / "results.jsonl").exists()
