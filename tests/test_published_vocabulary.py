"""Every published schema spells the shared vocabulary exactly as its type does: the result
statuses (`agent_contract.tools.RESULT_STATUSES`), the flight state (`FlightState`), the bus's
failsafe reasons and actions (read from STATUSTEXT by `parse_statustext`), and the truth event
kinds (`TruthEventKind`) wherever a surface lists them: the OpenAI tools, the MCP tools' output
schemas, the REST API's OpenAPI description and the MQTT payload schemas."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import httpx

from agent_contract.tools import RESULT_STATUSES
from benchmark.server import Hub, Role, create_app
from emulator.truth_events import TruthEventKind
from llm_tools import OUTPUT_SCHEMA, default_registry, openai_tools
from llm_tools.mcp_server import build_server
from llm_tools.registry import served_registry
from mavlink_vocabulary import TELEMETRY_FLIGHT_STATES, FlightState
from mqtt_bus.payloads import FAILSAFE_ACTIONS, FAILSAFE_REASONS
from mqtt_bus.schemas import SCHEMAS

Lists = list[tuple[str, list[Any]]]


def _listed(schema: Any, path: str = "") -> Iterator[tuple[str, list[Any]]]:
    """(path, values) of every enum (a const counts as a list of one) in a schema, the path
    ending in the property that holds it."""
    if isinstance(schema, dict):
        if isinstance(schema.get("enum"), list):
            yield path, schema["enum"]
        if "const" in schema:
            yield path, [schema["const"]]
        for key, value in schema.items():
            yield from _listed(value, f"{path}/{key}")
    elif isinstance(schema, list):
        for value in schema:
            yield from _listed(value, path)


def _of(lists: Lists, name: str) -> list[list[Any]]:
    return [values for path, values in lists if path.rsplit("/", 1)[-1] == name]


async def _surfaces() -> dict[str, Lists]:
    from mcp import Client
    hub = Hub()
    hub.add_key("key-admin", Role.ADMIN, None)
    transport = httpx.ASGITransport(app=create_app(hub))
    async with httpx.AsyncClient(transport=transport, base_url="http://rest") as client:
        openapi = (await client.get("/openapi.json", headers={"X-API-Key": "key-admin"})).json()
    async with Client(build_server(served_registry(), lambda: None)) as client:
        mcp = [t.output_schema for t in (await client.list_tools()).tools]
    return {
        "openai": list(_listed(openai_tools(default_registry()))),
        "tool results": list(_listed(OUTPUT_SCHEMA)),
        "mcp": list(_listed(mcp)),
        "rest": list(_listed(openapi)),
        "mqtt": list(_listed(SCHEMAS)),
    }


async def test_statuses_and_flight_states_are_the_types() -> None:
    surfaces = await _surfaces()
    statuses = list(RESULT_STATUSES)
    every_state = [s.value for s in FlightState]
    for name in ("tool results", "mcp", "rest"):
        lists = surfaces[name]
        assert _of(lists, "status") and all(v == statuses for v in _of(lists, "status")), name
        states = _of(lists, "flight_state")
        assert states and all(v == every_state for v in states), name
    mqtt = surfaces["mqtt"]
    assert [v for v in _of(mqtt, "status") if v != ["online", "offline"]] == [statuses]
    assert _of(mqtt, "flight_state") == [[s.value for s in TELEMETRY_FLIGHT_STATES]]
    assert _of(mqtt, "reason") == [list(FAILSAFE_REASONS)]
    assert _of(mqtt, "action") == [list(FAILSAFE_ACTIONS)]
    assert FAILSAFE_REASONS == ("battery_critical", "battery_emergency", "offboard_lost",
                                "geofence")
    assert FAILSAFE_ACTIONS == ("returning_home", "landing", "hold")


async def test_every_list_of_flight_states_is_the_type() -> None:
    """On every surface (the OpenAI tools' inputs included), wherever a flight state is
    listed."""
    surfaces = await _surfaces()
    generated = ([s.value for s in FlightState], [s.value for s in TELEMETRY_FLIGHT_STATES])
    found = [(name, values) for name, lists in surfaces.items()
             for values in _of(lists, "flight_state")]
    assert len(found) >= 4
    assert all(values in generated for _, values in found), found


async def test_truth_event_kinds_are_published_nowhere() -> None:
    """No surface lists the truth event kinds (ground truth stays hidden from agents); a list
    naming two of them would be a leak or a hand-written copy. The one reader that lists some,
    the replay page's colours, is checked against the type in test_truth_events.py."""
    kinds = {k.value for k in TruthEventKind}
    surfaces = await _surfaces()
    listing = [(name, path, values) for name, lists in surfaces.items()
               for path, values in lists if len(kinds & set(map(str, values))) > 1]
    assert listing == []
