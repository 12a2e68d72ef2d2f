"""Hostile input on the agent surfaces (REST, the tool registry, MCP): each reproduction gets a
specific 4xx error (an error result from the registry, `isError` over MCP) that names the
field, echoes at most a short preview, and changes nothing; the server answers afterwards."""

from __future__ import annotations

from collections.abc import AsyncIterator
from typing import Any

import httpx
import pytest

from benchmark.server import LiveSession
from emulator.radio import Radio, RadioError
from emulator.truth import TruthRecorder
from llm_tools import default_registry
from llm_tools.input_limits import MAX_BODY_BYTES
from llm_tools.mcp_server import build_server
from tests.rest_fixtures import KEYS, served

pytestmark = pytest.mark.mavsdk

HUGE = "1" + "0" * 400  # beyond float range
LONG = "7" * 5000  # beyond Python's integer-string limit
DEEP = "[" * 100_000
ECHO_LIMIT = 600  # characters any refusal may take


def raw_object(**fields: str) -> str:
    """JSON object text with each value given as raw JSON text (numbers no parser could
    hold, escapes no encoder would write)."""
    return "{" + ", ".join(f'"{key}": {value}' for key, value in fields.items()) + "}"


def _snapshot(live: LiveSession) -> tuple[Any, int]:
    """What a refusal must leave unchanged: every drone's state and the calls charged."""
    states = [(s.drone, s.armed, s.flight_state, round(s.altitude_m, 3))
              for s in live.gateway.list_drones()]
    return states, live.tools.tool_calls


def _refused(r: httpx.Response, status: int, *needles: str) -> str:
    assert r.status_code == status, (r.status_code, r.text[:300])
    body = r.json()
    text = str(body.get("detail", body.get("message")))
    assert len(r.text) < ECHO_LIMIT, len(r.text)
    for needle in needles:
        assert needle in text, (needle, text)
    return text


async def test_huge_long_and_deep_numbers_get_422_naming_the_field() -> None:
    async with served(role="agent") as s:
        client, live = s.client, s.live
        sid = live.session.id
        before = _snapshot(live)
        tool = f"/sessions/{sid}/tools/take_off"
        drone = next(iter(live.gateway.drones))
        for number in (HUGE, LONG, "1e400", "NaN", "-Infinity"):
            r = await client.post(tool, content=raw_object(drone_id=f'"{drone}"',
                                                           altitude_m=number))
            _refused(r, 422, "take_off: altitude_m")
        r = await client.post(tool, content=DEEP)
        _refused(r, 422, "nests deeper than 32 levels")
        generic = f"/drones/{drone}/command"
        for number in (HUGE, LONG):
            r = await client.post(generic, content=raw_object(
                command='"take_off"', parameters=raw_object(altitude=number)))
            _refused(r, 422, "parameters.altitude")
        _refused(await client.post(generic, content=DEEP), 422, "nests deeper")
        path = f"/drones/{drone}/command/move_along_path"
        for number in (HUGE, LONG):
            r = await client.post(path, content=f"[{raw_object(x=number, y='1')}]")
            _refused(r, 422, "[0].x")
        _refused(await client.post(path, content=DEEP), 422, "nests deeper")
        assert _snapshot(live) == before
        r = await client.post(tool, json={"drone_id": drone, "altitude_m": 8.0})
        assert r.status_code == 200 and r.json()["status"] == "ok", r.text


async def test_query_numbers_are_plain_ascii_decimals() -> None:
    async with served(role="agent") as s:
        client, live = s.client, s.live
        drone = next(iter(live.gateway.drones))
        before = _snapshot(live)
        for text in ("1_0", "\u0661\u0660", "0x10", " 1e999", "inf", "nan", "1" * 60):
            r = await client.post(f"/drones/{drone}/command/take_off",
                                  params={"altitude": text})
            _refused(r, 422, "parameter 'altitude'")
        assert _snapshot(live) == before


async def test_echoes_are_bounded() -> None:
    async with served(role="agent") as s:
        client, live = s.client, s.live
        sid = live.session.id
        drone = next(iter(live.gateway.drones))
        name = "n" * 1_000_000
        r = await client.post(f"/sessions/{sid}/tools/take_off",
                              json={"drone_id": "d1", "altitude_m": 5, name[:60]: 1})
        _refused(r, 422, "unknown argument(s)")
        r = await client.post(f"/sessions/{sid}/tools/land",
                              json={"drone_id": drone, name[:1000]: 1})
        _refused(r, 422, "is 1000 characters long; the limit is 64")
        r = await client.post(f"/drones/{drone}/command",
                              json={"command": name[:5000], "parameters": {}})
        _refused(r, 404, "unknown command 'nnn")
        r = await client.post(f"/drones/{drone}/command",
                              json={"command": name, "parameters": {}})
        _refused(r, 422, "command is 1000000 characters long")
        r = await client.post(f"/sessions/{sid}/tools/take_off",
                              json={"drone_id": name, "altitude_m": 5})
        _refused(r, 422, "drone_id is 1000000 characters long")


async def test_body_over_the_limit_gets_413_and_changes_nothing() -> None:
    async with served(role="agent") as s:
        client, live = s.client, s.live
        sid = live.session.id
        before = _snapshot(live)
        big = b'{"drone_id": "' + b"x" * MAX_BODY_BYTES + b'"}'
        r = await client.post(f"/sessions/{sid}/tools/land", content=big)
        _refused(r, 413, f"the limit is {MAX_BODY_BYTES}")

        async def chunks() -> AsyncIterator[bytes]:  # no Content-Length: counted as it streams
            for _ in range(20):
                yield b" " * (MAX_BODY_BYTES // 8)

        r = await client.post(f"/sessions/{sid}/tools/land", content=chunks())
        _refused(r, 413, "the limit is")
        assert _snapshot(live) == before
        assert (await client.get(f"/sessions/{sid}/drones")).status_code == 200


async def test_unencodable_text_is_refused_and_no_inbox_is_lost() -> None:
    async with served(role="agent") as s:
        client, live = s.client, s.live
        sid = live.session.id
        first, second = list(live.gateway.drones)[:2]
        tools = f"/sessions/{sid}/tools"
        r = await client.post(f"{tools}/send_message",
                              json={"drone_id": second, "to_drone_id": first, "text": "hello"})
        assert r.status_code == 200 and r.json()["status"] == "ok", r.text
        for text in ('"\\udc00"', '"ok \\ud800 then"', '"bell \\u0007"'):
            r = await client.post(f"{tools}/send_message", content=raw_object(
                drone_id=f'"{second}"', to_drone_id=f'"{first}"', text=text))
            _refused(r, 422, "send_message: text holds")
        r = await client.post(f"/drones/{second}/command", content='{"command": "broadcast", '
                              '"parameters": {"message": "\\udc00"}}')
        _refused(r, 422, "parameters.message holds a lone surrogate")
        r = await client.post(f"{tools}/read_messages", json={"drone_id": first})
        assert r.status_code == 200, r.text
        assert [m["text"] for m in r.json()["messages"]] == ["hello"]


def test_the_radio_refuses_unsendable_text_and_keeps_the_inbox() -> None:
    radio = Radio(["d1", "d2"], TruthRecorder(["d1", "d2"]), lambda: 0.0)
    radio.send("d2", "d1", "kept")
    for text in ("\udc00", "a\x00b", "\x1b[2J"):
        with pytest.raises(RadioError, match="unsendable character"):
            radio.send("d2", "d1", text)
        with pytest.raises(RadioError, match="unsendable character"):
            radio.broadcast("d2", text)
    assert [m.text for m in radio.read("d1")] == ["kept"]
    radio.send("d2", "d1", "tab\tand\nnewline are fine")


class _NoTools:
    """Stands where a task's tools would be: any use of it fails the test, since every call
    below must be refused before it reaches the tools."""

    def __getattr__(self, name: str) -> Any:
        raise AssertionError(f"a refused call reached the tools ({name})")


HOSTILE_ARGUMENTS: list[Any] = [
    raw_object(drone_id='"d1"', altitude_m=HUGE),
    raw_object(drone_id='"d1"', altitude_m=LONG),
    DEEP,
    {"drone_id": "d1", "altitude_m": 10**400},
    {"drone_id": "d1", "altitude_m": -(10**5000)},
    {"drone_id": "\udc00", "altitude_m": 5},
    {"drone_id": "d1", "altitude_m": float("nan")},
    {"x" * 1_000_000: 1},
    {("tuple", "key"): 1},
    {"drone_id": "d1", "altitude_m": {1, 2}},
    "\udc00",
    b"bytes",
    [1, 2, 3],
    '{"drone_id": "d1"' + ', "a": 1' * 200_000 + "}",
]


@pytest.mark.parametrize("arguments", HOSTILE_ARGUMENTS, ids=range(len(HOSTILE_ARGUMENTS)))
async def test_registry_call_never_raises(arguments: Any) -> None:
    deep: Any = 0
    for _ in range(10_000):
        deep = [deep]
    registry = default_registry()
    for args in (arguments, {"drone_id": "d1", "altitude_m": deep}):
        result = await registry.call(_NoTools(), "take_off", args)  # type: ignore[arg-type]
        assert result["status"] == "error" and result["message"].startswith("take_off: ")
        assert len(result["message"]) < ECHO_LIMIT
    for name in ("x" * 1_000_000, None, 12, ["take_off"]):
        result = await registry.call(_NoTools(), name, {})  # type: ignore[arg-type]
        assert result["status"] == "error" and len(result["message"]) < ECHO_LIMIT


async def test_mcp_answers_hostile_arguments_with_is_error() -> None:
    from mcp import Client
    async with served(role="agent") as s:
        live = s.live
        before = _snapshot(live)
        async with Client(build_server(default_registry(), lambda: live.tools)) as client:
            drone = next(iter(live.gateway.drones))
            for value in (10**400, -(10**5000), float("inf")):
                result = await client.call_tool("take_off",
                                                 {"drone_id": drone, "altitude_m": value})
                assert result.is_error, result
                assert "altitude_m" in result.structured_content["message"]
            result = await client.call_tool("send_message", {
                "drone_id": drone, "to_drone_id": drone, "text": "\udc00"})
            assert result.is_error and "lone surrogate" in result.structured_content["message"]
            assert _snapshot(live) == before
            ok = await client.call_tool("list_drones", {})
            assert not ok.is_error


async def test_api_description_lists_only_the_callers_routes() -> None:
    async with served(role="agent") as s:
        client = s.client
        public = (await client.get("/openapi.json", headers={"X-API-Key": ""})).json()
        agent = (await client.get("/openapi.json")).json()
        operator = (await client.get("/openapi.json",
                                     headers={"X-API-Key": KEYS["operator"]})).json()
        admin = (await client.get("/openapi.json", headers={"X-API-Key": KEYS["admin"]})).json()
        assert public == agent
        for spec in (public, operator):
            assert not [p for p in spec["paths"] if p.startswith("/check")], spec["paths"]
            assert "checks" not in str(spec["paths"])
        assert "/check/sessions/{session_id}/task" in admin["paths"]
        assert "/sessions" in operator["paths"] and "/sessions" not in public["paths"]
        assert "/sessions/{session_id}/tools/{name}" not in operator["paths"]
        assert "post" in public["paths"]["/sessions/{session_id}/tools/{name}"]
        wrong = await client.get("/openapi.json", headers={"X-API-Key": "wrong"})
        assert wrong.status_code == 401
        for page in ("/docs", "/redoc"):
            r = await client.get(page, headers={"X-API-Key": ""})
            assert r.status_code == 200 and "/openapi.json" in r.text
