"""Every agent tool's result validates against its published output schema on every surface:
the REST tools route and the MCP server (the official `mcp` client), each served by uvicorn on
a real socket, and the OpenAI adapter (tool calls as the `openai` SDK types them). And every
surface's list of result statuses is the gateway's `Status` plus "error", from one type."""

from __future__ import annotations

import json
from collections.abc import Awaitable, Callable
from typing import Any

import httpx
import pytest
from jsonschema import Draft202012Validator
from openai.types.chat import ChatCompletionMessage

from agent_contract import AgentTask, AgentTools, TaskBudget
from agent_contract.tools import ERROR_STATUS, RESULT_STATUSES
from benchmark.authoring.session_file import session_from_dict
from benchmark.running.episode import swarm_gateway
from benchmark.server import Hub, LiveSession, Role, create_app
from llm_tools import OUTPUT_SCHEMA, default_registry, parse_tool_calls
from llm_tools.batch import BATCH
from llm_tools.mcp_server import streamable_http_app
from llm_tools.registry import ToolRegistry, served_registry
from mavlink_gateway import Gateway, Outcome, Status
from mqtt_bus.schemas import SCHEMAS
from tests.asgi_fixtures import listening
from tests.bench_fixtures import small_session

AGENT_KEY = "key-agent"
Call = Callable[[str, dict[str, Any]], Awaitable[dict[str, Any]]]


def _every_call(gateway: Gateway, registry: ToolRegistry) -> list[tuple[str, dict[str, Any]]]:
    """One call of every tool `registry` serves, in an order that flies one drone through them
    all."""
    first, second = sorted(gateway.drones)[:2]
    x, y, _ = gateway.drones[first].state().position_m
    calls: list[tuple[str, dict[str, Any]]] = [
        ("list_drones", {}), ("drone_state", {"drone_id": first}),
        ("nearby", {"drone_id": first}),
        ("take_off", {"drone_id": first, "altitude_m": 6.0}),
        ("move_to", {"drone_id": first, "x": x + 3.0, "y": y, "z": 6.0}),
        ("move_towards", {"drone_id": first, "heading_deg": 270.0, "distance_m": 2.0}),
        ("change_altitude", {"drone_id": first, "altitude_m": 7.0}),
        ("move_along_path", {"drone_id": first, "waypoints": [[x + 1.0, y], [x, y, 6.0]]}),
        ("hover", {"drone_id": first, "duration_s": 1.0}),
        ("rotate", {"drone_id": first, "heading_deg": 90.0}),
        ("take_photo", {"drone_id": first}),
        ("send_message", {"drone_id": second, "to_drone_id": first, "text": "hello"}),
        ("broadcast", {"drone_id": second, "text": "all clear"}),
        ("wait", {"drone_id": first, "duration_s": 1.0}),
        ("wait", {"drone_id": second, "duration_s": 1.0}),
        ("read_messages", {"drone_id": first}),
        ("set_home", {"drone_id": first}),
        ("return_home", {"drone_id": first}),
        ("land", {"drone_id": first}),
        ("charge", {"drone_id": first}),
        (BATCH, {"calls": [{"tool": "drone_state", "arguments": {"drone_id": first}},
                           {"tool": "wait", "arguments": {"drone_id": second,
                                                           "duration_s": 1.0}},
                           {"tool": "nearby", "arguments": {"drone_id": "nobody"}}]}),
        ("finish", {"summary": "done"}),
    ]
    served = {spec.name for spec in registry.specs()}
    calls = [(name, arguments) for name, arguments in calls if name in served]
    missing = served - {name for name, _ in calls}
    assert not missing, f"add a call of {sorted(missing)} to this test"
    return calls


def _tools(gateway: Gateway) -> AgentTools:
    return AgentTools(gateway, AgentTask("s", "t01", "fly", TaskBudget(200, 900.0)))


async def _check_every_tool(gateway: Gateway, registry: ToolRegistry, surface: str,
                            call: Call) -> None:
    validators = {spec.name: Draft202012Validator(spec.output_schema)
                  for spec in registry.specs()}
    problems = []
    results: dict[str, list[dict[str, Any]]] = {}
    for name, arguments in _every_call(gateway, registry):
        result = await call(name, arguments)
        results.setdefault(name, []).append(result)
        problems += [f"{surface} {name}: {e.message}"
                     for e in validators[name].iter_errors(result)]
    assert not problems, "\n".join(problems)
    flown = [results[n][0]["status"] for n in ("take_off", "move_to", "hover", "finish")]
    assert flown == ["ok"] * 4, (surface, results)
    for waited in results["wait"]:  # the message is the outcome's line; arrival a flag
        assert waited["status"] == "ok" and isinstance(waited["message"], str), waited
        assert isinstance(waited["message_arrived"], bool), waited
        assert 0.0 < waited["waited_s"] <= 1.0, waited
    for batch in results.get(BATCH, []):  # one result per call; a bad call its own answer
        assert [r["status"] for r in batch["results"]] == ["ok", "ok", "rejected"], batch


@pytest.mark.mavsdk
async def test_every_tool_result_validates_on_rest_mcp_and_openai() -> None:
    from mcp import Client
    data = small_session(["takeoff_hold"])
    session = session_from_dict(data, source="s.json")
    task = session.tasks[0]
    async with swarm_gateway(session, lockstep=True) as (swarm, services, gateway):
        registry, served = default_registry(), served_registry()

        # REST: the tools route of a live session, an agent key, over a real socket.
        tools = _tools(gateway)
        live = LiveSession(session, task, swarm, services, gateway, tools, services.clock_s())
        hub = Hub()
        hub.add_session(live)
        hub.add_key(AGENT_KEY, Role.AGENT, session.id)
        async with listening(create_app(hub)) as url, httpx.AsyncClient(
                base_url=url, headers={"X-API-Key": AGENT_KEY}, timeout=60.0) as http:
            listed = (await http.get(f"/sessions/{session.id}/tools")).json()
            assert {t["name"]: t["output_schema"] for t in listed} == {
                spec.name: spec.output_schema for spec in served.specs()}
            assert all(spec.output_schema == OUTPUT_SCHEMA
                       for spec in served.specs() if spec.name != BATCH)

            async def rest(name: str, arguments: dict[str, Any]) -> dict[str, Any]:
                r = await http.post(f"/sessions/{session.id}/tools/{name}", json=arguments)
                assert r.status_code == 200, (name, r.status_code, r.text)
                return dict(r.json())
            await _check_every_tool(gateway, served, "REST", rest)

        # MCP: Streamable HTTP, the official client (which checks structured content against
        # each tool's output schema itself and raises when it does not validate).
        current = [_tools(gateway)]
        async with listening(streamable_http_app(served, lambda: current[0])) as url, \
                Client(f"{url}/mcp") as client:
            listed = {t.name: t.output_schema for t in (await client.list_tools()).tools}
            assert listed == {spec.name: spec.output_schema for spec in served.specs()}

            async def mcp(name: str, arguments: dict[str, Any]) -> dict[str, Any]:
                result = await client.call_tool(name, arguments)
                assert result.structured_content is not None, name
                return dict(result.structured_content)
            await _check_every_tool(gateway, served, "MCP", mcp)

        # OpenAI: an assistant message as the SDK types it, parsed by the adapter, run by the
        # registry, and sent back as the tool message's JSON content.
        openai_tools = _tools(gateway)

        async def openai(name: str, arguments: dict[str, Any]) -> dict[str, Any]:
            message = ChatCompletionMessage.model_validate({
                "role": "assistant", "content": None, "tool_calls": [{
                    "id": "call_1", "type": "function",
                    "function": {"name": name, "arguments": json.dumps(arguments)}}]})
            (parsed,) = parse_tool_calls(message.model_dump())
            result = await registry.call(openai_tools, parsed.name, parsed.arguments)
            return dict(json.loads(json.dumps(result, allow_nan=False)))
        await _check_every_tool(gateway, registry, "OpenAI", openai)


def test_an_outcome_cannot_hide_its_own_fields_behind_its_data() -> None:
    for key in ("status", "message", "state"):
        with pytest.raises(ValueError, match=f"may not use the key.*'{key}'"):
            Outcome(Status.OK, "waited 1.0 s", data={key: False})
    assert Outcome(Status.OK, "m", data={"message_arrived": False}).to_dict() == {
        "status": "ok", "message": "m", "message_arrived": False}


async def test_every_surface_lists_the_statuses_of_the_one_type() -> None:
    from mcp import Client
    statuses = [s.value for s in Status] + [ERROR_STATUS]
    assert list(RESULT_STATUSES) == statuses
    assert {"unknown", "failed"} <= set(statuses)
    assert OUTPUT_SCHEMA["properties"]["status"]["enum"] == statuses
    assert SCHEMAS["services_reply"]["properties"]["status"]["enum"] == statuses
    from llm_tools.mcp_server import build_server
    async with Client(build_server(default_registry(), lambda: None)) as client:
        instructions = client.instructions
        listed = (await client.list_tools()).tools
    assert instructions is not None and f"({', '.join(statuses)})" in instructions
    assert all(t.output_schema is not None
               and t.output_schema["properties"]["status"]["enum"] == statuses for t in listed)
