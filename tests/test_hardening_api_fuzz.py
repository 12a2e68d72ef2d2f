"""Property-based fuzzing (hypothesis) of the agent surfaces against a real stepped swarm.

Inputs: JSON with huge, long, non-finite and negative-zero numbers, text with lone surrogates
and control characters, deep nesting, long names, random bytes and bodies over the size
limit, sent to every kind of route with valid and invalid tool, command and drone names.

Invariants, per surface:
- REST: never a 5xx; every answer is JSON of bounded size; a 4xx changes nothing (every
  drone's state and the calls charged are as before); the server answers afterwards.
- MCP over Streamable HTTP: never a 5xx and never a JSON-RPC internal error; a tool call is
  answered with a result (`isError` for refusals) or a parse/params error; an `isError`
  result moves no drone, and one for bad input (status "error") is not charged either;
  tools/list works afterwards.
- The tool registry: `call` returns a result with a known status, or raises only
  `BudgetExhausted`; an error result changes nothing.

Hypothesis runs derandomized (`derandomize=True`), so CI sees the same inputs every time.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
from collections.abc import Iterator
from typing import Any
from urllib.parse import quote

import httpx
import pytest
import uvicorn
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from agent_contract import BudgetExhausted
from benchmark.server import LiveSession
from llm_tools import default_registry
from llm_tools.input_limits import MAX_BODY_BYTES
from llm_tools.mcp_server import streamable_http_app
from tests.rest_fixtures import served
from tests.test_hardening_api import _snapshot, raw_object

pytestmark = [pytest.mark.mavsdk, pytest.mark.slow]

FUZZ = settings(derandomize=True, database=None, deadline=None, print_blob=True,
                suppress_health_check=list(HealthCheck))
STATUSES = {"ok", "partial", "blocked", "rejected", "timeout", "unknown", "failed", "error"}
MAX_ANSWER_CHARS = 50_000
TOOL_NAMES = [s.name for s in default_registry().specs()]
COMMANDS = ["take_off", "land", "move_to", "move_towards", "move_along_path", "hover",
            "rotate", "change_altitude", "send_message", "broadcast", "calibrate"]


class Raw(str):
    """A number written out as JSON text (an integer too long for Python's int parser)."""


def dump(value: Any) -> str:
    """JSON text of a fuzz value (Raw numbers verbatim, NaN/Infinity as Python writes them,
    surrogates as \\u escapes)."""
    if isinstance(value, Raw):
        return str.__str__(value)
    if isinstance(value, dict):
        return "{" + ",".join(f"{json.dumps(k)}:{dump(v)}" for k, v in value.items()) + "}"
    if isinstance(value, list):
        return "[" + ",".join(dump(v) for v in value) + "]"
    return json.dumps(value)


TEXT = st.text(st.characters(codec=None, exclude_categories=()), max_size=30)
NUMBERS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.integers(min_value=10**300, max_value=10**320),
    st.integers(min_value=31, max_value=6000).map(lambda n: Raw("9" * n)),
    st.sampled_from([Raw("1e400"), Raw("-0.0"), Raw("1E-400"), 5.0, 10, -1, 0]),
)
NAMES = st.one_of(st.sampled_from(["drone_id", "to_drone_id", "altitude_m", "x", "y", "z",
                                   "text", "waypoints", "heading_deg", "command",
                                   "parameters", "altitude", "message"]),
                  TEXT, st.integers(65, 3000).map(lambda n: "k" * n))
LEAVES = st.one_of(NUMBERS, TEXT, st.booleans(), st.none(),
                   st.sampled_from(["d1", "d2", "d3", "zz"]))
VALUES = st.recursive(LEAVES, lambda inner: st.lists(inner, max_size=4)
                      | st.dictionaries(NAMES, inner, max_size=4), max_leaves=12)
OBJECTS = st.dictionaries(NAMES, VALUES, max_size=5)
BODIES = st.one_of(
    OBJECTS.map(dump), VALUES.map(dump),
    st.integers(33, 150_000).map(lambda n: "[" * n), st.integers(33, 5000).map(
        lambda n: '{"a":' * n + "1" + "}" * n),
    st.binary(max_size=64).map(lambda b: b.decode("latin-1")),
    st.just('{"drone_id":"' + "x" * (MAX_BODY_BYTES + 10) + '"}'),
)


def _encode(body: str) -> bytes:
    return body.encode("utf-8", "surrogatepass")


@contextlib.contextmanager
def live_loop() -> Iterator[tuple[asyncio.AbstractEventLoop, httpx.AsyncClient, LiveSession]]:
    """A swarm served over REST in an event loop of its own, for synchronous property tests
    that run one request at a time with `loop.run_until_complete`."""
    loop = asyncio.new_event_loop()
    context = served(role="agent")
    ready = loop.run_until_complete(context.__aenter__())
    client, live = ready.client, ready.live
    try:
        yield loop, client, live
    finally:
        loop.run_until_complete(context.__aexit__(None, None, None))
        loop.close()


async def _settled(live: LiveSession) -> tuple[Any, int]:
    await asyncio.wait_for(live.swarm.wait_idle(), 30.0)
    return _snapshot(live)


def test_rest_fuzz_never_5xx_and_refusals_change_nothing() -> None:
    with live_loop() as (loop, client, live):
        sid = live.session.id
        drones = list(live.gateway.drones)

        @settings(FUZZ, max_examples=150)
        @given(route=st.integers(0, 3), name=st.one_of(st.sampled_from(TOOL_NAMES + COMMANDS),
                                                       TEXT), drone=st.one_of(
                   st.sampled_from(drones), TEXT), body=BODIES,
               query=st.dictionaries(st.sampled_from(["altitude", "x", "heading", "dx",
                                                      "distance", "message", "session"]),
                                     st.one_of(NUMBERS.map(dump), TEXT), max_size=3))
        def check(route: int, name: str, drone: str, body: str, query: dict[str, str]) -> None:
            name_q, drone_q = quote(name, safe="", errors="replace"), quote(
                drone, safe="", errors="replace")
            path = [f"/sessions/{sid}/tools/{name_q}", f"/drones/{drone_q}/command",
                    f"/drones/{drone_q}/command/{name_q}",
                    f"/sessions/{sid}/drones/{drone_q}"][route]
            before = loop.run_until_complete(_settled(live))
            method = "GET" if route == 3 else "POST"
            r = loop.run_until_complete(client.request(
                method, path, content=_encode(body), params=query))
            assert r.status_code < 500, (path, r.status_code, r.text[:300])
            event(f"HTTP {r.status_code}")
            assert len(r.text) < MAX_ANSWER_CHARS
            if not r.is_redirect:  # e.g. a trailing slash left by an empty name
                r.json()
            if r.status_code >= 400:
                assert _snapshot(live) == before, (path, r.status_code, r.text[:300])

        check()
        r = loop.run_until_complete(client.get(f"/sessions/{sid}/drones"))
        # still serving; the fuzz may have called `finish` with valid arguments (which of its
        # examples it draws depends on the literals of the code base), and then the task's
        # tools are rightly refused
        answer = r.json()
        assert r.status_code == 200 and (answer["status"] == "ok" or answer["message"].endswith(
            "the task is already finished")), r.text[:400]


def test_registry_fuzz_never_raises_and_errors_change_nothing() -> None:
    registry = default_registry()
    with live_loop() as (loop, _, live):

        @settings(FUZZ, max_examples=300)
        @given(name=st.one_of(st.sampled_from(TOOL_NAMES), TEXT),
               arguments=st.one_of(OBJECTS, BODIES, VALUES))
        def check(name: str, arguments: Any) -> None:
            before = loop.run_until_complete(_settled(live))
            if isinstance(arguments, dict) and any(isinstance(v, Raw) for v in
                                                   arguments.values()):
                arguments = dump(arguments)
            try:
                result = loop.run_until_complete(registry.call(live.tools, name, arguments))
            except BudgetExhausted:
                return
            assert result["status"] in STATUSES and isinstance(result["message"], str)
            event(f"status {result['status']}")
            if result["status"] == "error":
                assert len(result["message"]) < 2000
                assert _snapshot(live) == before, result

        check()


async def _mcp_post(client: httpx.AsyncClient, url: str, body: bytes,
                    session: str | None) -> httpx.Response:
    headers = {"Accept": "application/json, text/event-stream",
               "Content-Type": "application/json", "MCP-Protocol-Version": "2025-06-18"}
    if session:
        headers["Mcp-Session-Id"] = session
    return await client.post(url, content=body, headers=headers)


async def _mcp_serve(live: LiveSession) -> tuple[uvicorn.Server, asyncio.Task[None], str]:
    app = streamable_http_app(default_registry(), lambda: live.tools, json_response=True)
    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=0, log_level="error",
                                           lifespan="on"))
    task = asyncio.create_task(server.serve())
    while not server.started:
        await asyncio.sleep(0.01)
    port = server.servers[0].sockets[0].getsockname()[1]
    return server, task, f"http://127.0.0.1:{port}/mcp"


def test_mcp_http_fuzz_answers_without_internal_errors() -> None:
    with live_loop() as (loop, _, live):
        server, task, url = loop.run_until_complete(_mcp_serve(live))
        http = httpx.AsyncClient(timeout=60.0)
        init = {"jsonrpc": "2.0", "id": 0, "method": "initialize", "params": {
            "protocolVersion": "2025-06-18", "capabilities": {},
            "clientInfo": {"name": "fuzz", "version": "0"}}}
        r = loop.run_until_complete(_mcp_post(http, url, json.dumps(init).encode(), None))
        assert r.status_code == 200, r.text
        session = r.headers["mcp-session-id"]
        note = b'{"jsonrpc":"2.0","method":"notifications/initialized"}'
        loop.run_until_complete(_mcp_post(http, url, note, session))

        @settings(FUZZ, max_examples=120)
        @given(name=st.one_of(st.sampled_from(TOOL_NAMES), TEXT), arguments=BODIES,
               request_id=st.integers(1, 10**6))
        def check(name: str, arguments: str, request_id: int) -> None:
            before = loop.run_until_complete(_settled(live))
            body = raw_object(jsonrpc='"2.0"', id=str(request_id), method='"tools/call"',
                              params=raw_object(name=json.dumps(name), arguments=arguments))
            r = loop.run_until_complete(_mcp_post(http, url, _encode(body), session))
            assert r.status_code < 500, (r.status_code, r.text[:300])
            if not r.content:
                return
            answer = r.json()
            event("JSON-RPC error" if "error" in answer else
                  f"isError {answer.get('result', {}).get('isError')}")
            if "error" in answer:
                assert answer["error"]["code"] != -32603, answer
            elif answer.get("result", {}).get("isError"):
                states, calls = _snapshot(live)
                assert states == before[0], answer  # a refusal moves nothing
                if answer["result"]["structuredContent"]["status"] == "error":
                    assert calls == before[1], answer  # and bad input is not charged

        try:
            check()
            listed = {"jsonrpc": "2.0", "id": 1, "method": "tools/list"}
            r = loop.run_until_complete(_mcp_post(http, url, json.dumps(listed).encode(),
                                                  session))
            assert r.status_code == 200 and len(r.json()["result"]["tools"]) == len(TOOL_NAMES)
        finally:
            loop.run_until_complete(http.aclose())
            server.should_exit = True
            loop.run_until_complete(task)
