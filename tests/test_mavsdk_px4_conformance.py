"""PX4 conformance through the real MAVSDK client (native binding) over UDP: the official
examples' offboard velocity-body circle and multi-vehicle local frames, checked
against the ground truth."""

from __future__ import annotations

import math

import numpy as np
import pytest
from mavsdk.asyncio.plugins.offboard import OffboardAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync
from mavsdk.plugins.offboard import PositionNedYaw, VelocityBodyYawspeed
from mavsdk.plugins.telemetry import FlightMode

from tests.mavsdk_helpers import eventually, first, take_off, truth_pos

pytestmark = pytest.mark.mavsdk


def _rows_since(swarm, sysid: int, t0_s: float) -> np.ndarray:
    rows = swarm.recorder.trajectory(f"d{sysid}")
    return rows[rows[:, 0] >= t0_s]


async def test_velocity_body_with_yawspeed_flies_a_circle(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(1, speed=5.0)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        system = systems[0]
        offboard, telemetry = OffboardAsync(system), TelemetryAsync(system)
        await take_off(swarm, system, 1, 8.0)
        # the official offboard_velocity_body example's circle: forward 5 m/s, 30 deg/s
        await offboard.set_velocity_body(VelocityBodyYawspeed(5.0, 0.0, 0.0, 30.0))
        await offboard.start()
        await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.OFFBOARD, 3.0,
                    "OFFBOARD mode")
        t_start = swarm.fleet.now_s
        await eventually(lambda: swarm.fleet.now_s > t_start + 16.0, 10.0, "16 s flown")
        rows = _rows_since(swarm, 1, t_start + 4.0)  # once on the circle
        turned = np.sum((np.diff(rows[:, 4]) + 180.0) % 360.0 - 180.0)
        assert turned / (rows[-1, 0] - rows[0, 0]) == pytest.approx(30.0, rel=0.03)
        xy = rows[:, 1:3]
        r = np.hypot(*(xy - xy.mean(axis=0)).T)
        assert r.mean() == pytest.approx(5.0 / math.radians(30.0), rel=0.05)
        assert np.ptp(r) < 0.5
        await offboard.stop()


async def test_each_vehicle_flies_its_own_local_frame(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(3, speed=5.0)
    async with mavsdk_client(swarm.ports.api_port, 3) as systems:
        for sysid in (2, 3):
            await take_off(swarm, systems[sysid - 1], sysid, 6.0)
        for sysid in (2, 3):
            telemetry = TelemetryAsync(systems[sysid - 1])
            pv = await first(telemetry.subscribe_position_velocity_ned(), lambda v: True, 3.0,
                             "local position")
            assert math.hypot(pv.position.north_m, pv.position.east_m) < 0.2
            offboard = OffboardAsync(systems[sysid - 1])
            await offboard.set_position_ned(PositionNedYaw(12.0, 0.0, -8.0, 0.0))
            await offboard.start()
        aps = swarm.fleet.autopilots
        await eventually(lambda: math.dist(truth_pos(swarm, 2), (5.0, 12.0, 8.0)) < 0.5
                         and math.dist(truth_pos(swarm, 3), (10.0, 12.0, 8.0)) < 0.5, 10.0,
                         "each vehicle 12 m north of its own start")
        assert aps[1].mode.name == aps[2].mode.name == "OFFBOARD"
