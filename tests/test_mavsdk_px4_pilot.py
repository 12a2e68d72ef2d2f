"""PX4 conformance through the real MAVSDK client (native binding) over UDP: the official
manual_control example's joystick input (POSCTL and ALTCTL) and the follow_me example's
target, checked against the ground truth."""

from __future__ import annotations

import asyncio
import contextlib
import math
from collections.abc import AsyncIterator

import numpy as np
import pytest
from mavsdk.asyncio.plugins.follow_me import FollowMeAsync
from mavsdk.asyncio.plugins.manual_control import ManualControlAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync
from mavsdk.plugins.follow_me import Config, TargetLocation
from mavsdk.plugins.telemetry import FlightMode

from emulator.clock import ClockConfig
from tests.mavsdk_helpers import eventually, first, geodetic, take_off, truth_pos

pytestmark = pytest.mark.mavsdk


class Joystick:
    """Sends the current stick input at 20 Hz, as a ground station's joystick does."""

    def __init__(self, manual: ManualControlAsync) -> None:
        self.manual = manual
        self.sticks = (0.0, 0.0, 0.5, 0.0)  # pitch, roll, throttle (0..1), yaw

    async def run(self) -> None:
        while True:
            await self.manual.set_manual_control_input(*self.sticks)
            await asyncio.sleep(0.05)


@contextlib.asynccontextmanager
async def joystick(manual: ManualControlAsync) -> AsyncIterator[Joystick]:
    stick = Joystick(manual)
    await manual.set_manual_control_input(*stick.sticks)  # as the example: input first
    task = asyncio.create_task(stick.run())
    try:
        yield stick
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task


async def test_manual_control_example_flies_posctl_and_altctl(swarm_factory,
                                                              mavsdk_client) -> None:
    swarm = await swarm_factory(1, speed=5.0)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        system = systems[0]
        manual, telemetry = ManualControlAsync(system), TelemetryAsync(system)
        await take_off(swarm, system, 1, 10.0)
        ap = swarm.fleet.autopilots[0]
        async with joystick(manual) as stick:
            await manual.start_position_control()
            await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.POSCTL,
                        3.0, "POSCTL mode")
            x0, y0, z0 = truth_pos(swarm, 1)
            heading = math.radians(float(swarm.fleet.dyn.yaw_deg[0]))
            stick.sticks = (1.0, 0.0, 0.5, 0.0)  # full forward
            await eventually(lambda: math.dist(truth_pos(swarm, 1)[:2], (x0, y0)) > 30.0, 10.0,
                             "30 m flown forward")
            x1, y1, z1 = truth_pos(swarm, 1)
            along = (x1 - x0) * math.sin(heading) + (y1 - y0) * math.cos(heading)
            assert along == pytest.approx(math.hypot(x1 - x0, y1 - y0), rel=0.01)
            assert z1 == pytest.approx(z0, abs=0.2)
            assert swarm.fleet.dyn.speed_m_s(0) == pytest.approx(ap.params["MPC_VEL_MANUAL"],
                                                                 rel=0.05)
            stick.sticks = (0.0, 0.0, 0.5, 0.0)  # centred: brakes and holds
            await eventually(lambda: swarm.fleet.dyn.speed_m_s(0) < 0.05, 10.0, "stopped")
            here = truth_pos(swarm, 1)
            t0 = swarm.fleet.now_s
            await eventually(lambda: swarm.fleet.now_s > t0 + 3.0, 5.0, "3 s held")
            assert math.dist(truth_pos(swarm, 1), here) < 0.1
            await manual.start_altitude_control()
            await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.ALTCTL,
                        3.0, "ALTCTL mode")
            stick.sticks = (0.0, 0.0, 1.0, 0.0)  # full throttle: climbs
            await eventually(lambda: truth_pos(swarm, 1)[2] > here[2] + 10.0, 10.0,
                             "10 m climbed")
            assert ap.mode.name == "ALTCTL"
        # the joystick stops: after COM_RC_LOSS_T the failsafe (NAV_RCL_ACT 2) returns home
        await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.RETURN_TO_LAUNCH,
                    5.0, "RTL after the joystick was lost")
        failsafes = swarm.recorder.events("d1", kinds="failsafe")
        assert [e.data["reason"] for e in failsafes] == ["manual_control_lost"]


async def test_follow_me_example_follows_the_target_at_the_configured_distance(
        swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(1, clock=ClockConfig(stepped=True))
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        system = systems[0]
        follow_me, telemetry = FollowMeAsync(system), TelemetryAsync(system)
        await take_off(swarm, system, 1, 10.0)
        # 12 m to the target's left (-90 deg), 15 m above home
        await follow_me.set_config(Config(15.0, 12.0, 0.1, Config.FollowAltitudeMode.CONSTANT,
                                          5.0, -90.0))
        ap = swarm.fleet.autopilots[0]
        assert (ap.params["FLW_TGT_HT"], ap.params["FLW_TGT_DST"],
                ap.params["FLW_TGT_FA"]) == (15.0, 12.0, -90.0)
        await follow_me.start()
        await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.FOLLOW_ME,
                    3.0, "FOLLOW_ME mode")
        # The phone's reports pace simulated time: each is the target's position at the
        # moment it arrives (the clock is held until it has), then one simulated second runs,
        # so what the vehicle knows does not depend on how loaded the machine is.
        hold = swarm.pin()
        t0 = swarm.fleet.now_s

        def target_at(t_s):  # walking north-east at 2 m/s from (20, 0)
            d = 2.0 / math.sqrt(2.0) * (t_s - t0)
            return 20.0 + d, d

        v = 2.0 / math.sqrt(2.0)
        for _ in range(50):
            now = swarm.fleet.now_s
            x, y = target_at(now)
            lat, lon, alt = geodetic(swarm, x, y, 0.0)
            await follow_me.set_target_location(TargetLocation(lat, lon, alt, v, v, 0.0))
            await eventually(lambda at=now: ap.follow.fix is not None
                             and ap.follow.fix.t_s == at, 5.0, "the phone's report")
            hold, released = swarm.hold_clock_at(now + 1.0), hold
            swarm.release_clock(released)
            await swarm.advance(1.0)
        swarm.release_clock(hold)
        rows = swarm.recorder.trajectory("d1")
        rows = rows[(rows[:, 0] >= t0 + 30.0) & (rows[:, 0] <= t0 + 50.0)]
        tx, ty = target_at(rows[:, 0])
        dx, dy = rows[:, 1] - tx, rows[:, 2] - ty
        # left of a north-east walker: north-west of it, 12 m off, at 15 m
        left = np.array([-1.0, 1.0]) / math.sqrt(2.0) * 12.0
        off = np.hypot(dx - left[0], dy - left[1])
        assert off.max() < 0.05, (np.percentile(off, 95), off.max())
        assert np.abs(rows[:, 3] - 15.0).max() < 0.1
        await follow_me.stop()
        await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.HOLD, 3.0,
                    "HOLD after follow-me")
