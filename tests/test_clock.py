"""The simulated clock seen through a real MAVSDK client: speed-up and stepped determinism."""

from __future__ import annotations

import asyncio
import concurrent.futures
import time

import numpy as np
import pytest
from mavsdk.asyncio import ComponentType, Configuration, Mavsdk
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync

from emulator.clock import ClockConfig
from emulator.scenario import default_scenario
from emulator.swarm import PortPlan, Swarm
from tests.ports import unused_udp_port

pytestmark = pytest.mark.mavsdk


async def _fly(clock: ClockConfig, pause_s: float) -> tuple[Swarm, float]:
    """Arm, take off, go somewhere, land: with `pause_s` of client idleness between steps."""
    asyncio.get_running_loop().set_default_executor(concurrent.futures.ThreadPoolExecutor(16))
    port = unused_udp_port()
    ports = PortPlan(bind_host="127.0.0.1", api_port=port, gcs_port=0)
    swarm = Swarm(default_scenario(1), clock=clock, ports=ports)
    # No disarm for want of a take-off: at 20x it comes 0.5 s of wall time after arming, which
    # a loaded machine's MAVSDK round trips can take (the take-off was then denied).
    swarm.fleet.autopilots[0].set_param("COM_DISARM_PRFLT", -1.0)
    async with swarm, Mavsdk(Configuration.create_with_component_type(
        ComponentType.GROUND_STATION
    )) as mavsdk:
        await mavsdk.add_any_connection(f"udpin://0.0.0.0:{port}")
        system = await mavsdk.first_autopilot(timeout_s=10.0)
        assert system is not None
        action, telemetry = ActionAsync(system), TelemetryAsync(system)
        async for health in telemetry.subscribe_health():
            if health.is_armable and health.is_home_position_ok:
                break
        start = time.monotonic()
        await action.arm()
        await asyncio.sleep(pause_s)
        await action.takeoff()
        async for mode in telemetry.subscribe_flight_mode():
            if mode.name == "HOLD":
                break
        await asyncio.sleep(pause_s)
        home = await telemetry.home()
        await action.goto_location(home.latitude_deg + 0.002, home.longitude_deg + 0.001,
                                   home.absolute_altitude_m + 10.0, 0.0)
        async for _position in telemetry.subscribe_position():
            ap = swarm.fleet.autopilots[0]
            if not swarm.fleet.any_busy and ap.position_m[1] > 200.0:
                break
        await asyncio.sleep(pause_s)
        await action.land()
        async for armed in telemetry.subscribe_armed():
            if not armed:
                break
        return swarm, time.monotonic() - start


async def test_stepped_truth_does_not_depend_on_client_pauses():
    stepped = ClockConfig(stepped=True)
    quick, _ = await _fly(stepped, pause_s=0.0)
    slow, _ = await _fly(stepped, pause_s=1.0)
    a, b = quick.recorder.trajectory("d1"), slow.recorder.trajectory("d1")
    moving_a, moving_b = a[np.diff(a[:, 1:4], axis=0, prepend=a[:1, 1:4]).any(axis=1)], \
        b[np.diff(b[:, 1:4], axis=0, prepend=b[:1, 1:4]).any(axis=1)]
    assert moving_a.shape == moving_b.shape and moving_a.shape[0] > 100
    assert np.abs(moving_a - moving_b).max() < 1e-9
    kinds = lambda rec: [(e.t_s, e.kind) for e in rec.events("d1")]  # noqa: E731
    assert kinds(quick.recorder) == kinds(slow.recorder)


async def test_speed_20_completes_about_20_times_faster():
    swarm, wall_s = await _fly(ClockConfig(speed=20.0), pause_s=0.0)
    landed = swarm.recorder.events("d1", kinds=["disarm"])[-1].t_s
    armed = swarm.recorder.events("d1", kinds=["arm"])[0].t_s
    ratio = (landed - armed) / wall_s
    assert 12.0 <= ratio <= 21.0, f"simulated/wall = {ratio:.1f}"
