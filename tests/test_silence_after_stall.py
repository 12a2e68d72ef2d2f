"""A drone is judged silent (and a command to it tried only once) only when its telemetry is
missing after the call itself: telemetry that merely waited behind a long computation in this
process's event loop (the emulator's and the gateway's, on a loaded machine) is taken in
first, so the command keeps every try."""

from __future__ import annotations

import asyncio
import math
import time
from types import SimpleNamespace

import pytest

from benchmark.authoring.session_file import load_session
from benchmark.authoring.suite import SESSIONS_DIR
from benchmark.running.episode import reset_for_task, swarm_gateway
from mavlink_gateway.command_send import COMMAND_TRIES, SILENT_WALL_S, NoAnswer, send_command

pytestmark = [pytest.mark.mavsdk, pytest.mark.slow]


class Unanswered(Exception):
    """What MAVSDK raises when a command got no ACK."""

    result = SimpleNamespace(name="TIMEOUT")


async def _tries_after_a_stall(stall_s: float) -> int:
    session = load_session(SESSIONS_DIR / "area_search-easy-1.json")
    async with swarm_gateway(session, lockstep=True) as (swarm, services, gateway):
        await reset_for_task(swarm, services, gateway)
        link = gateway.drones["d1"]
        calls = []

        async def call() -> None:
            calls.append(1)
            raise Unanswered

        async def refresh() -> bool:
            return True

        time.sleep(stall_s)  # the loop is busy: neither the swarm nor the gateway runs
        with pytest.raises(NoAnswer):
            await send_command(link, "a test command", call, goal=None, sent=lambda: None,
                               refresh=refresh)
        return len(calls)


async def test_a_drone_is_not_silent_because_the_loop_was_busy() -> None:
    assert await _tries_after_a_stall(SILENT_WALL_S + 0.5) == COMMAND_TRIES


async def test_a_drone_that_stays_silent_is_tried_once() -> None:
    session = load_session(SESSIONS_DIR / "area_search-easy-1.json")
    async with swarm_gateway(session, lockstep=True) as (swarm, _services, gateway):
        link = gateway.drones["d1"]
        swarm.streams.period_s[0] = swarm.streams.next_due_s[0] = math.inf  # nothing more
        swarm.left.add(0)  # comes: d1 sends no stream and no burst
        await asyncio.sleep(0.5)  # what was already on its way has come
        link.last_update_wall_s -= SILENT_WALL_S + 1  # as if nothing came for that long

        calls = []

        async def call() -> None:
            calls.append(1)
            raise Unanswered

        async def refresh() -> bool:
            return True

        with pytest.raises(NoAnswer, match="after 1 try"):
            await send_command(link, "a test command", call, goal=None, sent=lambda: None,
                               refresh=refresh)
        assert len(calls) == 1
