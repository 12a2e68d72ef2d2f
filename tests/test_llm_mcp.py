"""The MCP server, through the official MCP client: tool listing with schemas, and calls on a
real stepped swarm, in-process and over Streamable HTTP."""

from __future__ import annotations

import asyncio
import contextlib
import json
import sys
from collections.abc import AsyncIterator
from typing import TYPE_CHECKING, Any

import pytest

from agent_contract import AgentTask, AgentTools
from agent_contract.protocol import TaskBudget
from benchmark.authoring.session_file import session_from_dict
from benchmark.running.episode import swarm_gateway
from llm_tools import OUTPUT_SCHEMA, default_registry
from llm_tools.mcp_server import build_server, call_result, streamable_http_app
from mavlink_gateway import Gateway
from tests.asgi_fixtures import listening
from tests.bench_fixtures import small_session

if TYPE_CHECKING:
    import mcp_types as types

BUDGET = TaskBudget(tool_calls=50, sim_time_s=600.0)


def _task_tools(gateway: Gateway, budget: TaskBudget = BUDGET) -> AgentTools:
    return AgentTools(gateway, AgentTask("s", "t01", "take off", budget))


def _payload(result: types.CallToolResult) -> dict[str, Any]:
    """The structured content, after checking the text block carries the same JSON."""
    import mcp_types as types
    (block,) = result.content
    assert isinstance(block, types.TextContent)
    assert block.text == json.dumps(result.structured_content, separators=(",", ":"),
                                    ensure_ascii=False)
    return dict(result.structured_content)


@contextlib.asynccontextmanager
async def _http_url(app: Any) -> AsyncIterator[str]:
    """Serve an ASGI app on a free local port, in this event loop: its MCP endpoint."""
    async with listening(app) as url:
        yield f"{url}/mcp"


@contextlib.asynccontextmanager
async def _swarm() -> AsyncIterator[tuple[Gateway, str, float]]:
    data = small_session(["takeoff_hold"])
    op = data["tasks"][0]["oracle"][0][0]
    async with swarm_gateway(session_from_dict(data, source="s.json")) as (_, _, gateway):
        yield gateway, op["drone"], float(op["altitude_m"])


def _on_ground(gateway: Gateway) -> dict[str, tuple[bool, str]]:
    return {d: (link.armed, link.flight_state) for d, link in gateway.drones.items()}


async def test_lists_every_tool_with_strict_input_and_shared_output_schema() -> None:
    from mcp import Client
    registry = default_registry()
    async with Client(build_server(registry, lambda: None)) as client:
        listed = (await client.list_tools()).tools
    assert [t.name for t in listed] == [s.name for s in registry.specs()]
    assert len(listed) == 20
    for tool in listed:
        assert tool.input_schema["additionalProperties"] is False, tool.name
        spec = registry.get(tool.name)
        assert spec is not None and tool.input_schema == spec.input_schema
        assert tool.output_schema == OUTPUT_SCHEMA
        assert tool.description
    take_off = next(t for t in listed if t.name == "take_off")
    assert take_off.input_schema["required"] == ["drone_id", "altitude_m"]


def test_call_result_flags_error_statuses_only() -> None:
    import mcp_types as types
    for status, flagged in [("ok", False), ("partial", False), ("blocked", False),
                            ("timeout", False), ("rejected", True), ("error", True)]:
        result = call_result({"status": status, "message": "m", "n": [1, 2]})
        assert result.is_error is flagged, status
        assert result.structured_content == {"status": status, "message": "m", "n": [1, 2]}
        (block,) = result.content
        assert isinstance(block, types.TextContent)
        assert block.text == f'{{"status":"{status}","message":"m","n":[1,2]}}'
    with pytest.raises(ValueError, match="string 'status'"):
        call_result({"message": "no status"})


async def test_calls_without_a_running_task_are_errors() -> None:
    from mcp import Client
    async with Client(build_server(default_registry(), lambda: None)) as client:
        idle = await client.call_tool("list_drones", {})
        unknown = await client.call_tool("teleport", {})
    assert idle.is_error and "no task is running" in _payload(idle)["message"]
    assert unknown.is_error and "unknown tool 'teleport'" in _payload(unknown)["message"]
    assert "take_off" in _payload(unknown)["message"]


@pytest.mark.slow
async def test_stdio_server_in_a_subprocess() -> None:
    from mcp import Client, StdioServerParameters
    code = ("import anyio; from llm_tools import default_registry; "
            "from llm_tools.mcp_server import serve_stdio; "
            "anyio.run(lambda: serve_stdio(default_registry(), lambda: None))")
    params = StdioServerParameters(command=sys.executable, args=["-c", code])
    async with Client(params) as client:
        listed = (await client.list_tools()).tools
        idle = await client.call_tool("take_off", {"drone_id": "d1", "altitude_m": 5.0})
    assert len(listed) == 20 and listed[0].output_schema == OUTPUT_SCHEMA
    assert idle.is_error and "no task is running" in _payload(idle)["message"]


@pytest.mark.mavsdk
async def test_in_process_client_flies_a_real_swarm() -> None:
    from mcp import Client
    async with _swarm() as (gateway, drone, altitude_m):
        tools = _task_tools(gateway)
        async with Client(build_server(default_registry(), lambda: tools)) as client:
            listed = await client.call_tool("list_drones", {})
            drones = _payload(listed)
            assert not listed.is_error and drones["status"] == "ok"
            assert sorted(d["drone"] for d in drones["drones"]) == sorted(gateway.drones)

            before = _on_ground(gateway)
            bad = {
                "unknown drone": await client.call_tool(
                    "take_off", {"drone_id": "zz9", "altitude_m": altitude_m}),
                "wrong type": await client.call_tool(
                    "take_off", {"drone_id": drone, "altitude_m": "high"}),
                "unknown tool": await client.call_tool("teleport", {"drone_id": drone}),
                "extra argument": await client.call_tool(
                    "take_off", {"drone_id": drone, "altitude_m": altitude_m, "speed": 3}),
            }
            for why, result in bad.items():
                assert result.is_error, why
                assert _payload(result)["status"] in ("error", "rejected"), why
            assert "zz9" in _payload(bad["unknown drone"])["message"]
            assert "altitude_m must be a number" in _payload(bad["wrong type"])["message"]
            assert "unknown tool 'teleport'" in _payload(bad["unknown tool"])["message"]
            assert "unknown argument(s) 'speed'" in _payload(bad["extra argument"])["message"]
            await asyncio.sleep(0.3)
            assert _on_ground(gateway) == before
            assert all(not armed for armed, _ in before.values())

            took_off = await client.call_tool("take_off",
                                              {"drone_id": drone, "altitude_m": altitude_m})
            flown = _payload(took_off)
            assert not took_off.is_error and flown["status"] == "ok", flown
            assert flown["state"]["drone"] == drone
            assert flown["state"]["altitude_m"] == pytest.approx(altitude_m, abs=1.0)
            assert gateway.drones[drone].armed


@pytest.mark.mavsdk
async def test_streamable_http_client_flies_a_real_swarm_and_sees_a_spent_budget() -> None:
    from mcp import Client
    async with _swarm() as (gateway, drone, altitude_m):
        current = [_task_tools(gateway)]
        app = streamable_http_app(default_registry(), lambda: current[0])
        async with _http_url(app) as url, Client(url) as client:
            listed = (await client.list_tools()).tools
            assert len(listed) == 20
            assert all(t.input_schema["additionalProperties"] is False for t in listed)

            bad = await client.call_tool("take_off", {"drone_id": drone, "altitude_m": True})
            assert bad.is_error and "altitude_m must be a number" in _payload(bad)["message"]
            assert not gateway.drones[drone].armed

            took_off = await client.call_tool("take_off",
                                              {"drone_id": drone, "altitude_m": altitude_m})
            assert not took_off.is_error, _payload(took_off)
            assert _payload(took_off)["state"]["altitude_m"] == pytest.approx(altitude_m,
                                                                               abs=1.0)

            current[0] = _task_tools(gateway, TaskBudget(tool_calls=1, sim_time_s=600.0))
            first = await client.call_tool("list_drones", {})
            spent = await client.call_tool("list_drones", {})
            again = await client.call_tool("drone_state", {"drone_id": drone})
            assert not first.is_error
            assert spent.is_error and "the task is over" in _payload(spent)["message"]
            assert "1 tool calls" in _payload(spent)["message"]
            assert again.is_error and "the task is over" in _payload(again)["message"]
            assert current[0].spent is not None and current[0].tool_calls == 1
