"""Property-based fuzzing (hypothesis, derandomized) of the console's command route: any body
(hostile numbers, lone surrogates, deep nesting, bytes that are not UTF-8, bodies over the size
limit; valid and invalid tools, drones and selections) is answered with a 4xx naming the
problem, never a 5xx, and while a benchmark task runs nothing reaches the gateway: the
commander is never even asked to open one."""

from __future__ import annotations

import asyncio
from typing import Any
from urllib.parse import quote

import httpx
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from console.app import ConsoleState, create_console_app
from console.auth import ConsoleAuth
from console.commands import COMMANDS, Commander
from console.live import LiveSwarm
from mavlink_gateway import Gateway
from tests.test_hardening_api_fuzz import BODIES, NUMBERS, TEXT, dump

FUZZ = settings(derandomize=True, database=None, deadline=None, print_blob=True,
                suppress_health_check=list(HealthCheck), max_examples=200)
DRONES = ["d1", "d2", "d3"]
REFUSAL = "session s is running benchmark task t01 for its agent"

ARGS = st.dictionaries(st.sampled_from(["altitude_m", "x", "y", "z", "duration_s", "drone_id"]),
                       st.one_of(NUMBERS, TEXT, st.none(), st.booleans()), max_size=4)
SELECTION = st.one_of(st.just("all"), st.lists(st.sampled_from([*DRONES, "d9"]), max_size=4),
                      TEXT, NUMBERS)
COMMAND_BODIES = st.one_of(
    st.fixed_dictionaries({"drone_id": st.one_of(st.sampled_from(DRONES), TEXT),
                           "tool": st.one_of(st.sampled_from(COMMANDS), TEXT)},
                          optional={"args": st.one_of(ARGS, NUMBERS, TEXT)}).map(dump),
    st.fixed_dictionaries({"drone_ids": SELECTION,
                           "tool": st.one_of(st.sampled_from(COMMANDS), TEXT)},
                          optional={"args": ARGS,
                                    "args_by_drone": st.dictionaries(
                                        st.sampled_from([*DRONES, "zz"]), ARGS, max_size=3)}
                          ).map(dump),
    BODIES,
)


def test_command_bodies_never_5xx_and_send_nothing_while_a_task_runs() -> None:
    opened: list[str] = []

    async def never_opened() -> Gateway:
        opened.append("gateway")
        raise AssertionError("a refused command opened the gateway")

    scene: dict[str, Any] = {"drones": [{"id": d, "position": {"x": 0.0, "y": 0.0, "z": 0.0}}
                                        for d in DRONES], "targets": [], "obstacles": []}
    commander = Commander("s", never_opened, refusal=lambda: REFUSAL)
    live = LiveSwarm("s", "fuzzed", scene, commander=commander)
    auth, key = ConsoleAuth.single_key("fuzz-key")
    app = create_console_app(ConsoleState(auth, {"s": live}))
    loop = asyncio.new_event_loop()
    client = httpx.AsyncClient(transport=httpx.ASGITransport(app=app), base_url="http://console")

    @FUZZ
    @given(body=COMMAND_BODIES, live_id=st.one_of(st.just("s"), TEXT))
    def check(body: str, live_id: str) -> None:
        answer = loop.run_until_complete(client.post(
            f"/api/live/{quote(live_id, safe='') or 's'}/command",
            content=body.encode("utf-8", "surrogatepass"),
            headers={"X-API-Key": key}))
        assert answer.status_code in (404, 409, 413, 422), (answer.status_code, answer.text)
        assert len(answer.text) < 5000
        if answer.status_code == 409:
            assert REFUSAL in answer.json()["detail"]

    try:
        check()
        valid = loop.run_until_complete(client.post(
            "/api/live/s/command", json={"drone_ids": "all", "tool": "hold"},
            headers={"X-API-Key": key}))
        assert valid.status_code == 409  # well-formed, and refused: a task runs
    finally:
        loop.run_until_complete(client.aclose())
        loop.close()
    assert opened == []
