"""Flying through MAVSDK's action and offboard plugins: take-off, goto, hold, land, RTL,
offboard set-points, arming refusals and landed states.

The real MAVSDK client (native binding) over UDP on 127.0.0.1, checked against the ground
truth."""

from __future__ import annotations

import asyncio
import math
import time
from typing import Any

import pytest
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.mission_raw import MissionRawAsync
from mavsdk.asyncio.plugins.offboard import OffboardAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync
from mavsdk.plugins.action import ActionError, ActionResult
from mavsdk.plugins.offboard import PositionNedYaw
from mavsdk.plugins.telemetry import FlightMode, LandedState

from emulator.swarm import Swarm
from tests.mavsdk_helpers import (
    eventually,
    first,
    geodetic,
    horizontal_error_m,
    kinds,
    max_speed_m_s,
    take_off,
    truth_pos,
    watching,
    waypoints_items,
)

pytestmark = pytest.mark.mavsdk


async def test_takeoff_altitude_goto_hold_land(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(2)
    async with mavsdk_client(swarm.ports.api_port, 2) as systems:
        system = systems[0]
        action, telemetry = ActionAsync(system), TelemetryAsync(system)
        ap = swarm.fleet.autopilots[0]

        await action.set_takeoff_altitude(12.5)  # PARAM_SET, waits for the PARAM_VALUE echo
        assert ap.params["MIS_TAKEOFF_ALT"] == pytest.approx(12.5)
        assert await action.get_takeoff_altitude() == pytest.approx(12.5)  # PARAM_REQUEST_READ

        await action.arm()
        assert ap.armed and "arm" in kinds(swarm, 1)
        await action.takeoff()
        await eventually(lambda: "takeoff_complete" in kinds(swarm, 1), 10.0, "takeoff complete")
        x, y, z = truth_pos(swarm, 1)
        assert z == pytest.approx(12.5, abs=0.3)
        assert math.hypot(x, y) < 0.5  # straight up from home (0, 0)
        pos = await first(telemetry.subscribe_position(),
                          lambda p: abs(p.relative_altitude_m - 12.5) < 0.3, 5.0,
                          "relative altitude 12.5 m")
        assert horizontal_error_m(swarm, pos.latitude_deg, pos.longitude_deg, 0.0, 0.0) < 0.5
        assert await telemetry.flight_mode() == FlightMode.HOLD

        # goto_location: 30 m east, 40 m north, 15 m above home, facing east
        lat, lon, alt = geodetic(swarm, 30.0, 40.0, 15.0)
        await action.goto_location(lat, lon, alt, 90.0)
        await eventually(lambda: not swarm.fleet.busy[0] and math.dist(
            truth_pos(swarm, 1), (30.0, 40.0, 15.0)) < 1.0, 10.0, "arrival at goto target")
        assert float(swarm.fleet.dyn.yaw_deg[0]) == pytest.approx(90.0, abs=2.0)
        pos = await first(telemetry.subscribe_position(),
                          lambda p: horizontal_error_m(swarm, p.latitude_deg, p.longitude_deg,
                                                       30.0, 40.0) < 1.0, 5.0,
                          "telemetry at goto target")
        assert pos.absolute_altitude_m == pytest.approx(alt, abs=1.0)
        assert max_speed_m_s(swarm, 1) <= ap.params["MPC_XY_VEL_MAX"] + 0.1  # flown, not jumped

        # hold: fly towards a far point, then hold half way; it must stop short and stay
        lat, lon, alt = geodetic(swarm, 30.0, 200.0, 15.0)
        await action.goto_location(lat, lon, alt, float("nan"))
        await eventually(lambda: truth_pos(swarm, 1)[1] > 70.0, 10.0, "flying north")
        await action.hold()
        await eventually(lambda: float(swarm.fleet.dyn.velocity_m_s[0][1]) < 0.05, 5.0,
                         "braking to a stop")
        stop = truth_pos(swarm, 1)
        assert 70.0 < stop[1] < 185.0  # stopped well short of the goto target at y = 200
        await asyncio.sleep(0.3)  # 6 s simulated
        assert math.dist(truth_pos(swarm, 1), stop) < 0.3
        assert await telemetry.flight_mode() == FlightMode.HOLD

        # disarming in the air is refused and changes nothing
        with pytest.raises(ActionError) as refused:
            await action.disarm()
        assert refused.value.result == ActionResult.COMMAND_DENIED
        assert ap.armed and ap.in_air
        assert math.dist(truth_pos(swarm, 1), stop) < 0.3

        # land: touches down below the hold point, then auto-disarms
        await action.land()
        await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.LAND, 3.0, "LAND")
        await first(telemetry.subscribe_landed_state(), lambda s: s == LandedState.ON_GROUND,
                    15.0, "ON_GROUND")
        await first(telemetry.subscribe_armed(), lambda a: not a, 5.0, "disarmed")
        x, y, z = truth_pos(swarm, 1)
        assert z == pytest.approx(0.0, abs=0.01)
        assert math.hypot(x - stop[0], y - stop[1]) < 0.5
        assert not ap.armed
        assert kinds(swarm, 1).index("landed") < kinds(swarm, 1).index("disarm")
        # the second vehicle did nothing
        assert truth_pos(swarm, 2) == pytest.approx((5.0, 0.0, 0.0))
        assert "arm" not in kinds(swarm, 2)

async def test_return_to_launch(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(3, speed=30.0)
    async with mavsdk_client(swarm.ports.api_port, 3) as systems:
        sysid = 3  # home at (10, 0): not the origin
        system = systems[sysid - 1]
        action, telemetry = ActionAsync(system), TelemetryAsync(system)
        ap = swarm.fleet.autopilots[sysid - 1]
        await action.set_return_to_launch_altitude(20.0)
        assert ap.params["RTL_RETURN_ALT"] == pytest.approx(20.0)
        await take_off(swarm, system, sysid, 8.0)
        lat, lon, alt = geodetic(swarm, 50.0, 30.0, 8.0)
        await action.goto_location(lat, lon, alt, float("nan"))
        await eventually(lambda: math.dist(truth_pos(swarm, sysid), (50.0, 30.0, 8.0)) < 1.0,
                         10.0, "arrival before RTL")
        t_rtl = swarm.fleet.now_s
        async with watching(telemetry.subscribe_flight_mode()) as modes:
            await action.return_to_launch()
            await modes.wait(lambda m: m == FlightMode.RETURN_TO_LAUNCH, 3.0, "RTL mode")
            await first(telemetry.subscribe_armed(), lambda a: not a, 20.0, "disarm after RTL")
        hx, hy, _ = ap.home_m
        x, y, z = truth_pos(swarm, sysid)
        assert math.hypot(x - hx, y - hy) < 1.0
        assert z == pytest.approx(0.0, abs=0.01)
        assert not ap.armed and not ap.in_air
        # it climbed to the return altitude before heading home
        rows = swarm.recorder.trajectory(f"d{sysid}", t_rtl)
        assert rows[:, 3].max() == pytest.approx(20.0, abs=0.5)
        events = [e.kind for e in swarm.recorder.events(f"d{sysid}", t_rtl)]
        assert events.index("landed") < events.index("disarm")
        await first(telemetry.subscribe_in_air(), lambda v: not v, 3.0, "in_air False")

async def test_offboard_position_setpoint_then_stop_holds(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(2)
    async with mavsdk_client(swarm.ports.api_port, 2) as systems:
        sysid = 2
        system = systems[sysid - 1]
        offboard, telemetry = OffboardAsync(system), TelemetryAsync(system)
        ap = swarm.fleet.autopilots[sysid - 1]
        await take_off(swarm, system, sysid, 6.0)
        # local NED about the vehicle's own origin (it started 5 m east of the session's):
        # 20 m north, 15 m east, 9 m up
        target = (5.0 + 15.0, 20.0, 9.0)
        await offboard.set_position_ned(PositionNedYaw(20.0, 15.0, -9.0, 45.0))
        await offboard.start()
        assert await offboard.is_active()
        await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.OFFBOARD, 3.0,
                    "OFFBOARD mode")
        await eventually(lambda: math.dist(truth_pos(swarm, sysid), target) < 0.5, 10.0,
                         "offboard setpoint reached")
        pv = await first(telemetry.subscribe_position_velocity_ned(),
                         lambda v: math.hypot(v.position.north_m - 20.0,
                                              v.position.east_m - 15.0) < 0.5,
                         5.0, "local position at the setpoint")
        assert pv.position.down_m == pytest.approx(-9.0, abs=0.5)
        assert float(swarm.fleet.dyn.yaw_deg[sysid - 1]) == pytest.approx(45.0, abs=2.0)
        assert ap.mode.name == "OFFBOARD"

        await offboard.stop()
        assert not await offboard.is_active()
        await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.HOLD, 3.0,
                    "HOLD after offboard stop")
        t_stop = swarm.fleet.now_s
        await asyncio.sleep(0.5)  # 10 s simulated without set-points
        assert ap.mode.name == "HOLD"
        assert math.dist(truth_pos(swarm, sysid), target) < 1.0
        assert ap.in_air
        assert not swarm.recorder.events(f"d{sysid}", t_stop, kinds="failsafe")

async def test_arm_denied_when_battery_low(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(2)
    async with mavsdk_client(swarm.ports.api_port, 2) as systems:
        action, telemetry = ActionAsync(systems[0]), TelemetryAsync(systems[0])
        await eventually(lambda: _armable(telemetry), 3.0, "health: armable at first")
        swarm.fleet.bat.pct[0] = 4.0  # below BAT_CRIT_THR (7 %)
        await eventually(lambda: swarm.fleet.bat.level[0] >= 2, 3.0, "battery level update")
        await eventually(lambda: _not_armable(telemetry), 3.0, "health: not armable")
        with pytest.raises(ActionError) as refused:
            await action.arm()
        assert refused.value.result == ActionResult.COMMAND_DENIED
        assert not swarm.fleet.autopilots[0].armed
        assert "arm" not in kinds(swarm, 1)
        assert await first(telemetry.subscribe_armed(), lambda v: True, 3.0, "armed") is False
        # a healthy vehicle in the same swarm still arms
        await ActionAsync(systems[1]).arm()
        assert swarm.fleet.autopilots[1].armed

async def _not_armable(telemetry: TelemetryAsync) -> bool:
    return not (await telemetry.health()).is_armable

async def test_takeoff_refused_when_disarmed(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(1)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        action, telemetry = ActionAsync(systems[0]), TelemetryAsync(systems[0])
        await eventually(lambda: _armable(telemetry), 3.0, "health: armable")
        with pytest.raises(ActionError) as refused:
            await action.takeoff()
        assert refused.value.result == ActionResult.COMMAND_DENIED
        await asyncio.sleep(0.2)  # 4 s simulated
        ap = swarm.fleet.autopilots[0]
        assert not ap.armed and not ap.in_air
        assert truth_pos(swarm, 1)[2] == 0.0
        assert "takeoff" not in kinds(swarm, 1)
        assert await first(telemetry.subscribe_in_air(), lambda v: True, 3.0, "in_air") is False

async def _armable(telemetry: TelemetryAsync) -> bool:
    return (await telemetry.health()).is_armable


# ------------------------------------------------------------- known flight-core bugs

async def _landed_states_after(telemetry: TelemetryAsync, swarm: Swarm, t_s: float,
                               timeout_s: float) -> list[Any]:
    """MAVSDK landed_state values that arrive after simulated time t_s (at least two)."""
    values: list[Any] = []
    async with watching(telemetry.subscribe_landed_state()) as states:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and len(values) < 2:
            await states.wait(lambda v: True, timeout_s, "landed_state")
            if swarm.fleet.now_s > t_s:
                values.extend(states.values[-1:])
            states.values.clear()
    return values

async def test_landed_state_in_air_during_mission_started_on_ground(swarm_factory,
                                                                    mavsdk_client) -> None:
    swarm = await swarm_factory(1)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        action, mission = ActionAsync(systems[0]), MissionRawAsync(systems[0])
        telemetry = TelemetryAsync(systems[0])
        await mission.upload_mission(
            waypoints_items(swarm, [(60.0, 0.0, 10.0), (60.0, 60.0, 10.0)]))
        await action.arm()
        await mission.start_mission()
        await eventually(lambda: "mission_item_reached" in kinds(swarm, 1), 10.0,
                         "first waypoint reached")
        assert swarm.fleet.autopilots[0].in_air
        t_cruise = swarm.fleet.now_s
        states = await _landed_states_after(telemetry, swarm, t_cruise, 4.0)
        assert states, "no landed_state while cruising to the second waypoint"
        assert all(s == LandedState.IN_AIR for s in states), states

async def test_landed_state_in_air_after_goto_during_takeoff(swarm_factory,
                                                             mavsdk_client) -> None:
    swarm = await swarm_factory(1)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        action, telemetry = ActionAsync(systems[0]), TelemetryAsync(systems[0])
        await action.set_takeoff_altitude(20.0)
        await action.arm()
        await action.takeoff()
        await eventually(lambda: truth_pos(swarm, 1)[2] > 3.0, 5.0, "climbing")
        lat, lon, alt = geodetic(swarm, 0.0, 30.0, 10.0)
        await action.goto_location(lat, lon, alt, float("nan"))
        await eventually(lambda: math.dist(truth_pos(swarm, 1), (0.0, 30.0, 10.0)) < 0.5, 10.0,
                         "arrival at the goto target")
        states = await _landed_states_after(telemetry, swarm, swarm.fleet.now_s, 4.0)
        assert states and all(s == LandedState.IN_AIR for s in states), states

async def test_landed_state_in_air_after_hold_interrupts_landing(swarm_factory,
                                                                 mavsdk_client) -> None:
    # 5x real time: the final descent from 3 m takes about 0.9 s of wall time, room for the
    # hold to arrive on a loaded machine (at 20x it had 0.2 s and sometimes came too late)
    swarm = await swarm_factory(1, speed=5.0)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        action, telemetry = ActionAsync(systems[0]), TelemetryAsync(systems[0])
        await take_off(swarm, systems[0], 1, 6.0)
        await action.land()
        await eventually(lambda: truth_pos(swarm, 1)[2] < 3.0, 10.0, "final descent")
        await action.hold()
        await asyncio.sleep(0.8)  # 4 s simulated: braked and hovering
        assert swarm.fleet.autopilots[0].in_air
        z = truth_pos(swarm, 1)[2]
        assert z > 0.5
        states = await _landed_states_after(telemetry, swarm, swarm.fleet.now_s, 4.0)
        assert truth_pos(swarm, 1)[2] == pytest.approx(z, abs=0.1)  # still hovering
        assert states and all(s == LandedState.IN_AIR for s in states), states
