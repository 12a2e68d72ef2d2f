"""Vehicles joining and leaving a running swarm (emulator.fleet_membership): a joined one is
a new MAVLink vehicle that MAVSDK discovers over real UDP and flies; a left one stops speaking
at once; its ground truth ends at its leave time; system ids are never reused."""

from __future__ import annotations

import asyncio
import time

import pytest
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync

from emulator.clock import ClockConfig
from emulator.fleet_membership import join, leave, present_ids
from emulator.services import SwarmServices
from tests.mavlink_client import running_swarm
from tests.mavsdk_helpers import eventually, first, kinds, take_off
from tests.scenario_fixtures import tiny_scenario, vehicle

pytestmark = pytest.mark.mavsdk


def _heartbeats(client, system: int, since: float) -> int:
    return sum(1 for r in client.received if r.t >= since and r.msg.get_type() == "HEARTBEAT"
               and r.msg.get_srcSystem() == system and r.msg.get_srcComponent() == 1)


async def test_mavsdk_discovers_and_flies_a_joined_vehicle(swarm_factory, mavsdk_client
                                                           ) -> None:
    swarm = await swarm_factory(scenario=tiny_scenario([vehicle(1), vehicle(2, 10.0)]))
    joined_s = swarm.fleet.now_s
    k = join(swarm, vehicle(3, 20.0, 5.0))
    assert k == 2 and swarm.n == 3 and present_ids(swarm.fleet) == ["d1", "d2", "d3"]
    async with mavsdk_client(swarm.ports.api_port, 3) as systems:
        assert [await s.get_system_id() for s in systems] == [1, 2, 3]
        joined = systems[2]
        position = await first(TelemetryAsync(joined).subscribe_position(),
                               lambda p: p.relative_altitude_m > -1.0, 5.0, "d3's position")
        assert position.latitude_deg != 0.0
        await take_off(swarm, joined, 3, 8.0)
        x, y, z = (float(v) for v in swarm.fleet.dyn.position_m[2])
        assert (x, y) == pytest.approx((20.0, 5.0), abs=0.5) and z == pytest.approx(8.0, abs=0.5)
        # the others did not move, and the truth holds d3's flight from its join on
        assert "arm" not in kinds(swarm, 1) and "arm" not in kinds(swarm, 2)
        rows = swarm.recorder.trajectory("d3")
        assert rows[0, 0] == pytest.approx(joined_s, abs=0.05)
        assert tuple(rows[0, 1:4]) == pytest.approx((20.0, 5.0, 0.0))
        assert rows[:, 3].max() > 7.0
        assert [e.kind for e in swarm.recorder.events("d3")][:1] == ["joined"]
        # MAVSDK sees a left vehicle go (no heartbeat) while the others stay connected
        leave(swarm, "d3")

        async def gone() -> bool:
            return not await joined.is_connected()

        await eventually(gone, 10.0, "MAVSDK to lose d3")
        assert await systems[0].is_connected() and await systems[1].is_connected()


async def test_a_left_vehicle_stops_speaking_and_ids_are_not_reused() -> None:
    async with running_swarm(2, speed=10.0) as (swarm, client):
        join(swarm, vehicle(3, 20.0))
        start = time.monotonic()
        await asyncio.sleep(1.6)
        assert _heartbeats(client, 3, start) >= 1, "the joined vehicle sends heartbeats"
        leave(swarm, "d2")
        left_at = time.monotonic()
        await asyncio.sleep(2.5)
        assert _heartbeats(client, 2, left_at + 0.05) == 0, "d2 still speaks after leaving"
        assert _heartbeats(client, 1, left_at) >= 2 and _heartbeats(client, 3, left_at) >= 2
        # a command to the left vehicle goes unanswered; its id is not given again
        client.send(client.mav.command_long_encode(2, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0))
        await asyncio.sleep(0.5)
        assert not any(r.msg.get_srcSystem() == 2 for r in client.received[client.mark:])
        with pytest.raises(ValueError, match="not reused"):
            join(swarm, vehicle(2))
        assert join(swarm, vehicle(4, 30.0)) == 3
        assert present_ids(swarm.fleet) == ["d1", "d3", "d4"]
        with pytest.raises(KeyError):
            leave(swarm, "d2")


async def test_truth_of_a_left_vehicle_ends_at_its_leave_time(swarm_factory) -> None:
    swarm = await swarm_factory(scenario=tiny_scenario([vehicle(1), vehicle(2, 10.0, 0.0, 5.0)]))
    await asyncio.sleep(0.5)
    leave(swarm, "d2")
    left_s = swarm.fleet.now_s
    await asyncio.sleep(1.0)
    assert swarm.fleet.now_s > left_s + 2.0  # speed 20: keyframes went by since
    rows = swarm.recorder.trajectory("d2")
    assert rows[-1, 0] <= left_s + 1e-9
    assert swarm.recorder.trajectory("d1")[-1, 0] > left_s + 1.0
    left = swarm.recorder.events("d2", kinds=["left"])
    assert len(left) == 1 and left[0].t_s == pytest.approx(left_s)
    assert left[0].data["position_m"] == pytest.approx([10.0, 0.0, 5.0])


async def test_perception_sees_a_joined_vehicle_and_not_a_left_one(swarm_factory) -> None:
    swarm = await swarm_factory(scenario=tiny_scenario([vehicle(1), vehicle(2, 10.0)]))
    services = SwarmServices(swarm)
    join(swarm, vehicle(3, 0.0, 20.0))
    services.add_drone("d3")
    seen = {v.id for v in services.sense("d1").vehicles}
    assert seen == {"d2", "d3"}
    assert {v.id for v in services.sense("d3").vehicles} == {"d1", "d2"}
    leave(swarm, "d2")
    services.remove_drone("d2")
    assert {v.id for v in services.sense("d1").vehicles} == {"d3"}
    with pytest.raises(KeyError):
        services.sense("d2")


async def test_a_lockstep_watch_on_a_leaving_vehicle_halts(swarm_factory) -> None:
    swarm = await swarm_factory(
        scenario=tiny_scenario([vehicle(1), vehicle(2, 10.0, 0.0, 5.0)]),
        clock=ClockConfig(stepped=True, lockstep=True))
    join(swarm, vehicle(3, 0.0, 10.0, 5.0))
    swarm.fleet.autopilots[1].reposition((300.0, 0.0, 5.0))
    swarm.fleet.autopilots[2].reposition((0.0, 300.0, 5.0))
    watch = swarm.watch("d2")
    assert not watch.halted_now() and swarm.fleet.busy[1]
    leave(swarm, "d2")  # before the scheduler stepped: d2 is on its way
    left_s = swarm.fleet.now_s
    halted_s = await asyncio.wait_for(watch.halted(), 2.0)
    assert halted_s == pytest.approx(left_s)
    assert swarm.fleet.dyn.position_m[1][0] < 100.0
    watch.close()
    # the joined vehicle flies on under the lockstep clock; d2 stays where it left
    at = swarm.fleet.dyn.position_m[1].copy()
    arrived = swarm.watch("d3")
    await asyncio.wait_for(arrived.halted(), 10.0)
    assert swarm.fleet.dyn.position_m[2][1] == pytest.approx(300.0, abs=2.0)
    assert (swarm.fleet.dyn.position_m[1] == at).all()
    arrived.close()
