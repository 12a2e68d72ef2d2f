"""The hosted agent inside an episode: it offers each task to the driver, serves it with the
task's key until the task ends, and then tells the driver; a taken task whose agent goes
silent (or never makes a request) ends as an agent error naming the reason, and the session
goes on to its next task; the token use an agent reports lands in its task's record."""

from __future__ import annotations

import asyncio
from pathlib import Path
from typing import Any

import httpx
import pytest

from benchmark.authoring.session_file import load_session
from benchmark.running.episode import run_session
from benchmark.running.hosted.agent import ExternalAgent
from tests.hosted_fixtures import session_file

pytestmark = pytest.mark.mavsdk


async def test_a_silent_agent_ends_its_task_and_the_next_is_offered(tmp_path: Path) -> None:
    session = load_session(session_file(tmp_path))
    notices: list[dict[str, Any]] = []
    records: list[dict[str, Any]] = []
    agent = ExternalAgent(session, lambda message: notices.append(message[1]),
                          idle_timeout_s=1.0)

    async def offer(count: int) -> dict[str, Any]:
        while len([n for n in notices if n["kind"] == "offer"]) < count:
            await asyncio.sleep(0.01)
        return [n for n in notices if n["kind"] == "offer"][count - 1]["offer"]

    async def external() -> None:
        async with httpx.AsyncClient(timeout=30.0) as http:
            first = await offer(1)
            # The driver's word that an agent took it (as /next sends it), then nothing.
            r = await http.post(f"{first['base_url']}/taken",
                                headers={"X-API-Key": first["key"]})
            assert r.status_code == 204
            second = await offer(2)
            key = {"X-API-Key": second["key"]}
            tokens = f"{second['base_url']}/sessions/current/tokens"
            for use in ({"prompt": 100, "completion": 20, "cost_usd": 0.5},
                        {"prompt": 1, "completion": 2}):
                r = await http.post(tokens, json=use, headers=key)
                assert r.status_code == 200, r.text
            for bad in ({"prompt": -1, "completion": 0}, {"prompt": 1}, {"prompt": 1,
                                                                         "completion": 1,
                                                                         "model": "x"}):
                r = await http.post(tokens, json=bad, headers=key)
                assert r.status_code == 422, (bad, r.text)
            r = await http.post(f"{second['tools_url']}/finish", json={}, headers=key)
            assert r.status_code == 200
            r = await http.post(f"{first['tools_url']}/drone_state", json={"drone_id": "d1"},
                                headers={"X-API-Key": first["key"]})
            assert r.status_code == 410 and "has ended" in r.text

    async with agent:
        client = asyncio.create_task(external())
        await run_session(session, agent, emit=records.append)
    await client
    assert [(r["task"], r["finish"]) for r in records] == [("t01", "agent_error"),
                                                          ("t02", "finished")]
    assert "no request for 1 s" in records[0]["error"] and records[0]["tool_calls"] == 0
    assert records[0]["tokens"] is None
    assert records[1]["tokens"] == {"prompt": 101, "completion": 22, "cost_usd": 0.5}
    kinds = [(n["kind"], n.get("offer", {}) and n["offer"]["task_id"]) for n in notices]
    assert [k for k, _ in kinds] == ["offer", "ended", "offer", "ended", "closed"]
    keys = [n["key"] for n in notices if n["kind"] == "ended"]
    assert keys == [n["key"] for n in notices if n["kind"] == "offer"] and len(set(keys)) == 2
