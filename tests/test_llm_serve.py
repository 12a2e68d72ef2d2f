"""Serving live sessions: `serve_rest` and `serve_mcp` started in this event loop on a free
port, called over real HTTP (httpx, the official MCP client), then cancelled; and the API-key
option parsing."""

from __future__ import annotations

import asyncio
import contextlib
import io
import json
from collections.abc import AsyncIterator, Callable, Coroutine
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import httpx
import pytest

from benchmark.authoring.session_file import dump_session
from benchmark.server import Hub, Role, create_app
from benchmark.server.serve import (
    ApiKey,
    _add_keys,
    generated_keys,
    live_hub,
    parse_api_key,
    serve_mcp,
    serve_rest,
)
from mavswarm.cli import main
from tests.bench_fixtures import small_session
from tests.cli_fixtures import MAVSWARM


@pytest.fixture(scope="module")
def session_data() -> dict[str, Any]:
    return small_session(["takeoff_hold"])


def _write(tmp_path: Path, data: dict[str, Any], name: str = "s.json") -> Path:
    path = tmp_path / name
    path.write_text(dump_session(data))
    return path


@contextlib.asynccontextmanager
async def _running(start: Callable[[Callable[[str], None]], Coroutine[Any, Any, None]]
                   ) -> AsyncIterator[str]:
    """Run a server coroutine as a task; yield its URL once ready; cancel it afterwards."""
    ready: asyncio.Future[str] = asyncio.get_running_loop().create_future()
    task = asyncio.create_task(start(ready.set_result))
    done, _ = await asyncio.wait({task, ready}, timeout=30.0,
                                 return_when=asyncio.FIRST_COMPLETED)
    if task in done:
        task.result()
    assert ready in done, "the server did not become ready within 30 s"
    try:
        yield ready.result()
    finally:
        task.cancel()
        with pytest.raises(asyncio.CancelledError):
            await task
        assert task.cancelled()


def test_parse_api_key_reads_role_session_and_key() -> None:
    assert parse_api_key("agent:area_search-easy-1=s3=cret") == ApiKey(
        Role.AGENT, "s3=cret", "area_search-easy-1")
    assert parse_api_key("agent=k") == ApiKey(Role.AGENT, "k", None)
    assert parse_api_key("admin=root") == ApiKey(Role.ADMIN, "root")
    assert parse_api_key("operator=op").spec() == "operator=op"
    assert parse_api_key(ApiKey(Role.AGENT, "k", "s1").spec()) == ApiKey(Role.AGENT, "k", "s1")


@pytest.mark.parametrize(("text", "message"), [
    ("agent", r"expected 'role\[:session\]=key'"),
    ("pilot=k", "role must be one of"),
    ("admin=", "the key after '=' is empty"),
    ("agent:=k", "the session after ':' is empty"),
    ("admin:s1=k", "only agent keys name a session"),
])
def test_parse_api_key_rejects_bad_specs(text: str, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        parse_api_key(text)


def test_keys_bind_to_sessions_and_generated_keys_cover_every_role() -> None:
    hub = Hub()
    for sid in ("s1", "s2"):
        hub.add_session(SimpleNamespace(id=sid))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="must name its session when several"):
        _add_keys(hub, [parse_api_key("agent=k")])
    with pytest.raises(ValueError, match="an agent key needs a session of the hub"):
        _add_keys(hub, [parse_api_key("agent:s9=k")])
    keys = generated_keys(["s1", "s2"])
    _add_keys(hub, keys)
    assert [(k.role, k.session_id) for k in keys] == [
        (Role.AGENT, "s1"), (Role.AGENT, "s2"), (Role.OPERATOR, None), (Role.ADMIN, None)]
    assert len({k.key for k in keys}) == 4
    assert hub.caller(keys[1].key) is not None and hub.caller(keys[1].key).session_id == "s2"

    single = Hub()
    single.add_session(SimpleNamespace(id="only"))  # type: ignore[arg-type]
    _add_keys(single, [parse_api_key("agent=k")])
    assert single.caller("k") is not None and single.caller("k").session_id == "only"


async def test_sessions_without_a_usable_task_are_refused_before_any_swarm(
        tmp_path: Path, session_data: dict[str, Any]) -> None:
    broken = {**session_data, "tasks": [{**session_data["tasks"][0], "budget": "lots"}]}
    with pytest.raises(ValueError, match="is not usable"):
        await serve_mcp(_write(tmp_path, broken), transport="http", port=0)
    same = _write(tmp_path, session_data, "twin.json")
    with pytest.raises(ValueError, match="is in both"):
        await serve_rest([_write(tmp_path, session_data), same], port=0)
    with pytest.raises(ValueError, match="transport"):
        await serve_mcp(same, transport="carrier-pigeon")  # type: ignore[arg-type]
    with pytest.raises(SystemExit):
        main(["serve", "--port", "1"])  # neither --sessions nor --suite


@pytest.mark.mavsdk
async def test_rest_server_over_real_http_with_keys(tmp_path: Path,
                                                    session_data: dict[str, Any]) -> None:
    path = _write(tmp_path, session_data)
    sid = session_data["id"]
    op = session_data["tasks"][0]["oracle"][0][0]
    out = io.StringIO()
    keys = ["agent=ag-key", "admin=ad-key"]

    def start(ready: Callable[[str], None]) -> Coroutine[Any, Any, None]:
        return serve_rest([path], host="127.0.0.1", port=0, keys=keys, on_ready=ready, out=out)

    async with _running(start) as url, httpx.AsyncClient(base_url=url, timeout=20.0) as client:
        agent = {"X-API-Key": "ag-key"}
        listed = await client.get(f"/sessions/{sid}/drones", headers=agent)
        assert listed.status_code == 200, listed.text
        drones = [d["drone"] for d in listed.json()["drones"]]
        assert sorted(drones) == sorted(d["id"] for d in session_data["drones"])

        wrong = await client.get(f"/sessions/{sid}/drones", headers={"X-API-Key": "nope"})
        assert wrong.status_code == 401

        took_off = await client.post(f"/sessions/{sid}/tools/take_off", headers=agent,
                                     json={"drone_id": op["drone"],
                                           "altitude_m": op["altitude_m"]})
        assert took_off.status_code == 200
        body = took_off.json()
        assert body["status"] == "ok", body
        assert body["state"]["altitude_m"] == pytest.approx(op["altitude_m"], abs=1.0)

        task = (await client.get(f"/sessions/{sid}/task", headers={"X-API-Key": "ad-key"})
                ).json()
        assert task["id"] == session_data["tasks"][0]["id"]
        assert task["tool_calls"] == 2  # list_drones and take_off, on the task's budget
        assert task["budget"] == session_data["tasks"][0]["budget"]
    assert f"REST API on {url}" in out.getvalue()
    assert "generated" not in out.getvalue()


@pytest.mark.mavsdk
async def test_rest_server_generates_and_prints_keys_when_none_are_given(
        tmp_path: Path, session_data: dict[str, Any]) -> None:
    path = _write(tmp_path, session_data)
    out = io.StringIO()

    def start(ready: Callable[[str], None]) -> Coroutine[Any, Any, None]:
        return serve_rest([path], port=0, on_ready=ready, out=out)

    async with _running(start) as url, httpx.AsyncClient(base_url=url) as client:
        printed = [line.strip() for line in out.getvalue().splitlines() if "=" in line]
        keys = {k.role: k for k in map(parse_api_key, printed)}
        assert keys[Role.AGENT].session_id == session_data["id"]
        r = await client.get("/sessions", headers={"X-API-Key": keys[Role.OPERATOR].key})
        assert r.status_code == 200 and [s["id"] for s in r.json()] == [session_data["id"]]
        r = await client.get("/sessions", headers={"X-API-Key": keys[Role.AGENT].key})
        assert r.status_code == 403


@pytest.mark.mavsdk
async def test_mcp_server_over_streamable_http(tmp_path: Path,
                                               session_data: dict[str, Any]) -> None:
    path = _write(tmp_path, session_data)
    op = session_data["tasks"][0]["oracle"][0][0]

    from mcp import Client

    def start(ready: Callable[[str], None]) -> Coroutine[Any, Any, None]:
        return serve_mcp(path, transport="http", host="127.0.0.1", port=0, on_ready=ready)

    async with _running(start) as url:
        assert url.endswith("/mcp")
        async with Client(url) as client:
            names = {t.name for t in (await client.list_tools()).tools}
            assert {"list_drones", "take_off", "drone_state"} <= names
            listed = await client.call_tool("list_drones", {})
            assert not listed.is_error
            ids = [d["drone"] for d in listed.structured_content["drones"]]
            assert sorted(ids) == sorted(d["id"] for d in session_data["drones"])
            took_off = await client.call_tool(
                "take_off", {"drone_id": op["drone"], "altitude_m": op["altitude_m"]})
            payload = json.loads(took_off.content[0].text)
            assert not took_off.is_error and payload["status"] == "ok", payload


@pytest.mark.mavsdk
async def test_mcp_server_over_stdio_in_a_subprocess(tmp_path: Path,
                                                     session_data: dict[str, Any]) -> None:
    from mcp import Client, StdioServerParameters  # the MCP SDK: only where a test uses it

    path = _write(tmp_path, session_data)
    params = StdioServerParameters(command=MAVSWARM[0], args=[*MAVSWARM[1:], "mcp", str(path)],
                                   cwd=str(Path(__file__).resolve().parents[1]))
    async with Client(params) as client:
        listed = await client.call_tool("list_drones", {})
    assert not listed.is_error, listed.content
    ids = [d["drone"] for d in listed.structured_content["drones"]]
    assert sorted(ids) == sorted(d["id"] for d in session_data["drones"])


@pytest.mark.mavsdk
async def test_a_world_without_tasks_is_served_as_free_flight(
        tmp_path: Path, session_data: dict[str, Any]) -> None:
    empty = _write(tmp_path, {**session_data, "tasks": []}, "world.json")
    async with live_hub([empty]) as hub:
        (live,) = hub.sessions.values()
        assert live.task.id == "free-flight" and live.task.checks is None
        drone = session_data["drones"][0]["id"]
        outcome = await live.tools.take_off(drone, 5.0)
        assert outcome.ok, outcome.message
        hub.add_key("k-admin", Role.ADMIN)
        transport = httpx.ASGITransport(app=create_app(hub))
        async with httpx.AsyncClient(transport=transport, base_url="http://rest") as client:
            check = await client.get(f"/check/sessions/{live.id}/task",
                                     headers={"X-API-Key": "k-admin"})
    assert check.status_code == 409 and "nothing to check" in check.json()["detail"]
