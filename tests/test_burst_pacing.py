"""Telemetry bursts (an operator reset, a lockstep halt) for a large swarm reach a real MAVSDK
client whole: the swarm sends a few vehicles' bursts per loop turn, because MAVSDK drops
subscription callbacks once one burst overflows its queue."""

from __future__ import annotations

import asyncio
import time

import pytest

from benchmark.authoring.session_file import load_session
from benchmark.authoring.suite import SESSIONS_DIR
from benchmark.running.episode import reset_for_task, swarm_gateway

pytestmark = [pytest.mark.mavsdk, pytest.mark.slow]

BURSTS = 6


async def test_every_burst_of_every_vehicle_of_a_30_drone_swarm_arrives() -> None:
    session = load_session(SESSIONS_DIR / "area_search-extreme-1.json")
    assert len(session.scenario.vehicles) == 30
    async with swarm_gateway(session, lockstep=True) as (swarm, services, gateway):
        await reset_for_task(swarm, services, gateway)
        before = {d: link.seen.get("landed_state", 0) for d, link in gateway.drones.items()}
        for _ in range(BURSTS):
            swarm.send_all_telemetry()
            await asyncio.sleep(0.25)
            # A burst asked for while a vehicle's last one still waits to go out is that one
            # (it will carry the newest state): on a loaded machine, wait for the swarm to
            # have sent them all, so that every request is a burst of its own.
            drained = time.monotonic() + 10.0
            while swarm.bursts.pending and time.monotonic() < drained:
                await asyncio.sleep(0.01)
            assert not swarm.bursts.pending, "a burst of 30 vehicles took over 10 s to go out"
        deadline = time.monotonic() + 5.0  # the last bursts may still be on their way

        def counted() -> dict[str, int]:
            return {d: link.seen.get("landed_state", 0) - before[d]
                    for d, link in gateway.drones.items()}

        while min(counted().values()) < BURSTS and time.monotonic() < deadline:
            await asyncio.sleep(0.05)
        got = counted()
        # each burst carries EXTENDED_SYS_STATE once (the 1 Hz stream adds one or two more)
        assert min(got.values()) >= BURSTS, got
        # a vehicle asked for alone goes first: its burst arrives while the others wait
        last = gateway.drones["d30"]
        mark = last.seen.get("battery", 0)
        swarm.send_all_telemetry()
        services.refresh_telemetry("d30")
        start = time.monotonic()
        while last.seen.get("battery", 0) < mark + 2 and time.monotonic() - start < 5.0:
            await last.wait_update(last.updates, 0.01)
        assert last.seen.get("battery", 0) >= mark + 2
