"""The threads of a served agent under the lockstep clock, and the batch tool.

The batch tool's schemas come from the registry's own tool specs; a bad batch is refused as a
whole and a bad call in a batch gets its own error. Over `serve`'s REST routes (uvicorn on a
free port, real HTTP): one agent key is one thread, so a second call while its first runs is
refused, the MultiUAV-Plat command routes included; per-drone keys are one thread each, the
clock running only while every drone's agent waits on the world.
"""

from __future__ import annotations

import asyncio
import contextlib
import io
import json
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any, cast

import httpx
import pytest

from agent_contract import AgentTools
from benchmark.running.tool_log import LoggedTools
from benchmark.server.hub import Hub, LiveSession
from benchmark.server.serve import parse_api_key, serve_rest
from llm_tools.batch import MAX_BATCH_CALLS
from llm_tools.mcp_server import mcp_tools
from llm_tools.registry import OUTPUT_SCHEMA, default_registry, served_registry
from tests.cli_fixtures import ROOT

SESSION = ROOT / "benchmark" / "sessions" / "target_assignment-easy-1.json"
SID = "target_assignment-easy-1"


def test_the_batch_schemas_are_generated_from_the_single_tool_specs() -> None:
    registry = served_registry()
    batch = registry.get("batch")
    assert batch is not None
    calls = batch.input_schema["properties"]["calls"]
    assert (calls["minItems"], calls["maxItems"]) == (1, MAX_BATCH_CALLS)
    variants = {v["properties"]["tool"]["enum"][0]: v["properties"]["arguments"]
                for v in calls["items"]["oneOf"]}
    assert variants == {s.name: s.input_schema for s in default_registry().specs()}
    assert "batch" not in variants
    assert batch.output_schema["properties"]["results"]["items"] == OUTPUT_SCHEMA
    listed = {t.name: t for t in mcp_tools(registry)}
    assert listed["batch"].output_schema == batch.output_schema
    assert listed["take_off"].output_schema == OUTPUT_SCHEMA
    assert "batch" not in {s.name for s in default_registry().specs()}  # models in-process


@pytest.mark.parametrize(("arguments", "problem"), [
    ("[1, 2]", "arguments must be a JSON object"),
    ({"calls": "take_off"}, "calls must be a list"),
    ({"calls": []}, "calls needs at least 1 item(s), got 0"),
    ({"calls": [{"tool": "list_drones"}] * (MAX_BATCH_CALLS + 1)},
     f"calls has {MAX_BATCH_CALLS + 1} items; the limit is {MAX_BATCH_CALLS}"),
    ({"calls": [{"tool": "list_drones"}], "then": 1}, "unknown argument(s) 'then'"),
])
async def test_a_bad_batch_is_refused_whole(arguments: Any, problem: str) -> None:
    # Nothing may run: the tools are not even there to run on.
    result = await served_registry().call(cast(AgentTools, None), "batch", arguments)
    assert result["status"] == "error" and problem in result["message"], result


async def test_bad_calls_in_a_batch_each_get_their_own_error() -> None:
    calls = [{"tool": "batch", "arguments": {"calls": []}}, {"tool": "fly"}, 7,
             {"tool": "hover", "arguments": [1]}, {"tool": "land", "drone": "d1"}]
    result = await served_registry().call(cast(AgentTools, None), "batch", {"calls": calls})
    assert result["status"] == "ok" and result["message"] == "5 calls: 5 error"
    messages = [r["message"] for r in result["results"]]
    assert "calls[0]: a batch cannot contain a batch" in messages[0]
    assert "calls[1].tool must name a tool" in messages[1] and "'fly'" in messages[1]
    assert "calls[2] must be an object" in messages[2]
    assert "calls[3].arguments must be a JSON object" in messages[3]
    assert "calls[4] has unknown key(s) 'drone'" in messages[4]


@contextlib.asynccontextmanager
async def _serving(tmp_path: Path, keys: list[str]
                   ) -> AsyncIterator[tuple[httpx.AsyncClient, LiveSession]]:
    data = json.loads(SESSION.read_text())
    data["tasks"] = data["tasks"][:1]
    path = tmp_path / "s.json"
    path.write_text(json.dumps(data))
    hubs: list[Hub] = []
    ready: asyncio.Future[str] = asyncio.get_running_loop().create_future()
    server = asyncio.create_task(serve_rest(
        [path], port=0, keys=keys, on_ready=ready.set_result, out=io.StringIO(),
        extend=lambda app, hub, keys: hubs.append(hub)))
    try:
        url = await asyncio.wait_for(ready, 60.0)
        async with httpx.AsyncClient(base_url=url, timeout=60.0) as client:
            yield client, hubs[0].sessions[SID]
    finally:
        server.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await server


async def _call(client: httpx.AsyncClient, key: str, tool: str, **args: Any) -> dict[str, Any]:
    reply = await client.post(f"/sessions/{SID}/tools/{tool}", json=args,
                              headers={"X-API-Key": key})
    assert reply.status_code in (200, 422), reply.text
    return dict(reply.json())


async def _until(condition: Any, what: str) -> None:
    for _ in range(2000):
        if condition():
            return
        await asyncio.sleep(0.005)
    raise AssertionError(f"{what} did not happen within 10 s")


@pytest.mark.mavsdk
async def test_one_key_is_one_thread_on_every_route(tmp_path: Path) -> None:
    async with _serving(tmp_path, ["agent=k", "admin=a"]) as (client, live):
        held = live.services.pin()  # another client of the swarm thinks: the clock stands
        flight = asyncio.create_task(_call(client, "k", "take_off", drone_id="d1",
                                           altitude_m=10.0))
        await _until(lambda: live.tools.tool_calls == 1, "the take-off")
        second = await _call(client, "k", "drone_state", drone_id="d2")
        assert second["status"] == "rejected" and "still running take_off" in second["message"]
        assert "batch" in second["message"] and "one key per drone" in second["message"]
        compat = (await client.post("/drones/d2/command/take_off", params={"altitude": 5},
                                    headers={"X-API-Key": "k"})).json()
        assert compat["status"] == "error" and "still running take_off" in compat["message"]
        batch = await _call(client, "k", "batch", calls=[{"tool": "list_drones"}])
        assert batch["status"] == "rejected" and batch["results"] == []
        assert live.tools.tool_calls == 1  # the refusals changed and counted nothing
        assert not flight.done()
        live.services.unpin(held)
        took_off = await flight
        assert took_off["status"] == "ok", took_off
        end_s = live.services.clock_s()
        await asyncio.sleep(0.3)  # the agent thinks: the clock waits for it
        assert live.services.clock_s() == end_s
        compat = (await client.post("/drones/d2/command/take_off", params={"altitude": 5},
                                    headers={"X-API-Key": "k"})).json()
        assert compat["status"] == "success", compat
        assert isinstance(live.tools, LoggedTools)
        log = live.tools.call_log()
        assert [c["name"] for c in log] == ["take_off", "take_off"]
        assert log[1]["t0_s"] == log[0]["t1_s"] == round(end_s, 3)


def test_drone_keys_parse_and_print() -> None:
    key = parse_api_key(f"agent:{SID}/d2=k2")
    assert (key.session_id, key.drone_id, key.key) == (SID, "d2", "k2")
    assert parse_api_key(key.spec()) == key
    with pytest.raises(ValueError, match="names its session and drone"):
        parse_api_key(f"agent:{SID}/=k")


@pytest.mark.mavsdk
async def test_per_drone_keys_are_threads_of_their_own(tmp_path: Path) -> None:
    keys = [f"agent:{SID}/d1=k1", f"agent:{SID}/d2=k2", "admin=a"]
    async with _serving(tmp_path, keys) as (client, live):
        start_s = live.services.clock_s()
        flight = asyncio.create_task(_call(client, "k1", "take_off", drone_id="d1",
                                           altitude_m=10.0))
        await _until(lambda: live.tools.tool_calls == 1, "d1's take-off")
        await asyncio.sleep(0.3)
        assert live.services.clock_s() == start_s  # d2's agent thinks: the clock waits
        assert not flight.done()
        other = await _call(client, "k2", "drone_state", drone_id="d1")
        assert other["status"] == "rejected" and "agent of d2" in other["message"]
        compat = (await client.post("/drones/d1/command/land",
                                    headers={"X-API-Key": "k2"})).json()
        assert compat["status"] == "error" and "one per drone" in compat["message"]
        first_wait = await _call(client, "k2", "wait", drone_id="d2", duration_s=2.0)
        assert first_wait["waited_s"] == pytest.approx(2.0)  # then d2 thinks again
        assert not flight.done()
        listening = asyncio.create_task(_call(client, "k2", "wait", drone_id="d2",
                                              duration_s=200.0))
        took_off = await flight
        assert took_off["status"] == "ok", took_off
        told_s = live.services.clock_s()
        sent = await _call(client, "k1", "broadcast", drone_id="d1", text="go")
        assert sent["status"] == "ok", sent
        assert (await _call(client, "k1", "finish", summary="up"))["status"] == "ok"
        heard = await listening  # d1's part is over: the clock runs for d2 alone
        assert 0.0 < heard["waited_s"] < 200.0
        read = await _call(client, "k2", "read_messages", drone_id="d2")
        assert [m["text"] for m in read["messages"]] == ["go"]
        assert not live.tools.finished
        assert (await _call(client, "k2", "finish", summary="heard"))["status"] == "ok"
        assert live.tools.finished and live.tools.summary == "d1: up; d2: heard"
        assert isinstance(live.tools, LoggedTools)
        log = {(c["name"], c["drone"]): c for c in live.tools.call_log()}
        assert log[("wait", "d2")]["t1_s"] > round(told_s, 3)


def test_serve_and_mcp_default_to_the_lockstep_clock_and_take_stepped() -> None:
    import argparse

    from benchmark.server.serve import add_parsers, generated_keys
    from benchmark.server.session_runner import SessionRunner

    parser = argparse.ArgumentParser()
    add_parsers(parser.add_subparsers())
    serve = parser.parse_args(["serve", "--sessions", "s.json"])
    assert (serve.clock, serve.keys_per_drone) == ("lockstep", False)
    assert parser.parse_args(["mcp", "s.json"]).clock == "lockstep"
    assert parser.parse_args(["mcp", "s.json", "--clock", "stepped"]).clock == "stepped"
    with pytest.raises(SystemExit):
        parser.parse_args(["serve", "--sessions", "s.json", "--clock", "wall"])
    with pytest.raises(ValueError, match="clock: expected one of lockstep, stepped"):
        SessionRunner(clock="wall")
    keys = generated_keys(["s1", "s2"], {"s1": ["d1", "d2"]})
    agents = [(k.session_id, k.drone_id) for k in keys if k.role.value == "agent"]
    assert agents == [("s1", "d1"), ("s1", "d2"), ("s2", None)]


@pytest.mark.mavsdk
async def test_a_session_has_drone_agents_or_one_agent_not_both(tmp_path: Path) -> None:
    from benchmark.server.serve import _add_keys, live_hub

    data = json.loads(SESSION.read_text())
    data["tasks"] = data["tasks"][:1]
    path = tmp_path / "s.json"
    path.write_text(json.dumps(data))
    async with live_hub([path]) as hub:
        both = [parse_api_key(f"agent:{SID}/d1=k1"), parse_api_key("agent=k")]
        with pytest.raises(ValueError, match="either one per drone or one for all"):
            _add_keys(hub, both)
    async with live_hub([path]) as hub:
        with pytest.raises(ValueError, match="'d9' is not a drone of session"):
            _add_keys(hub, [parse_api_key(f"agent:{SID}/d9=k9")])
