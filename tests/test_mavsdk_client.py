"""The emulator flown by the real MAVSDK client (native binding) over UDP on 127.0.0.1.

No mocks: every test starts a swarm, connects one MAVSDK ground station to it, drives it
through MAVSDK's plugins and checks what MAVSDK reports against the emulator's ground truth
(`swarm.recorder`, `swarm.fleet`). System id k is vehicle "dk" (index k - 1).
"""

from __future__ import annotations

import asyncio
import contextlib
import inspect
import math
import time
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any

import numpy as np
import pytest
from mavsdk.asyncio import Autopilot, Vehicle
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.camera import CameraAsync
from mavsdk.asyncio.plugins.mission_raw import MissionRawAsync
from mavsdk.asyncio.plugins.offboard import OffboardAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync
from mavsdk.plugins.action import ActionError, ActionResult
from mavsdk.plugins.mission_raw import MissionItem, MissionRawError, MissionRawResult
from mavsdk.plugins.offboard import PositionNedYaw
from mavsdk.plugins.telemetry import FlightMode, LandedState
from pymavlink.dialects.v20 import common as mavlink

from emulator.swarm import Swarm

pytestmark = pytest.mark.mavsdk

CAMERA_COMPONENT_ID = 100
FRAME_GLOBAL_RELATIVE_ALT_INT = 6
MAV_CMD_NAV_WAYPOINT = 16


# ------------------------------------------------------------------------------- helpers
class Watch:
    """Collects every value of a MAVSDK subscription in the background."""

    def __init__(self, stream: AsyncIterator[Any]) -> None:
        self.values: list[Any] = []
        self._new = asyncio.Event()
        self._task = asyncio.create_task(self._run(stream))

    async def _run(self, stream: AsyncIterator[Any]) -> None:
        async with contextlib.aclosing(stream) as it:  # type: ignore[type-var]
            async for value in it:
                self.values.append(value)
                self._new.set()

    async def wait(self, pred: Callable[[Any], bool], timeout_s: float, what: str) -> Any:
        """The first value (already seen or arriving) for which pred holds."""
        deadline = time.monotonic() + timeout_s
        seen = 0
        while True:
            for value in self.values[seen:]:
                if pred(value):
                    return value
            seen = len(self.values)
            left = deadline - time.monotonic()
            if left <= 0:
                last = self.values[-1] if self.values else None
                raise AssertionError(f"timed out after {timeout_s} s waiting for {what}; "
                                     f"{len(self.values)} values, last {last}")
            self._new.clear()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._new.wait(), left)

    async def close(self) -> None:
        self._task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await self._task


@contextlib.asynccontextmanager
async def watching(*streams: AsyncIterator[Any]) -> AsyncIterator[Any]:
    watches = [Watch(s) for s in streams]
    await asyncio.sleep(0.01)  # let every subscription register with MAVSDK
    try:
        yield watches[0] if len(watches) == 1 else watches
    finally:
        for w in watches:
            await w.close()


async def first(stream: AsyncIterator[Any], pred: Callable[[Any], bool], timeout_s: float,
                what: str) -> Any:
    async with watching(stream) as w:
        return await w.wait(pred, timeout_s, what)


async def eventually(cond: Callable[[], bool | Awaitable[bool]], timeout_s: float,
                     what: str) -> None:
    deadline = time.monotonic() + timeout_s
    while True:
        result = cond()
        if inspect.isawaitable(result):
            result = await result
        if result:
            return
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        await asyncio.sleep(0.02)


def truth_pos(swarm: Swarm, sysid: int) -> tuple[float, float, float]:
    """Latest recorded ENU position of system `sysid`."""
    row = swarm.recorder.trajectory(f"d{sysid}")[-1]
    return float(row[1]), float(row[2]), float(row[3])


def kinds(swarm: Swarm, sysid: int) -> list[str]:
    return [e.kind for e in swarm.recorder.events(f"d{sysid}")]


def geodetic(swarm: Swarm, x: float, y: float, z: float) -> tuple[float, float, float]:
    return swarm.fleet.world.origin.to_geodetic(x, y, z)


def horizontal_error_m(swarm: Swarm, lat: float, lon: float, x: float, y: float) -> float:
    px, py, _ = swarm.fleet.world.origin.to_local(lat, lon, 0.0)
    return math.hypot(px - x, py - y)


def max_speed_m_s(swarm: Swarm, sysid: int) -> float:
    """Largest horizontal speed between consecutive recorded samples (catches teleports)."""
    rows = swarm.recorder.trajectory(f"d{sysid}")
    dt = np.diff(rows[:, 0])
    step = np.hypot(np.diff(rows[:, 1]), np.diff(rows[:, 2]))
    return float((step[dt > 0] / dt[dt > 0]).max(initial=0.0))


async def take_off(swarm: Swarm, system: Any, sysid: int, altitude_m: float) -> None:
    """Arm, take off to `altitude_m` (via MIS_TAKEOFF_ALT) and wait until it holds there."""
    action, telemetry = ActionAsync(system), TelemetryAsync(system)
    await action.set_takeoff_altitude(altitude_m)
    await action.arm()
    await action.takeoff()
    ap = swarm.fleet.autopilots[sysid - 1]
    await eventually(lambda: ap.mode.name == "HOLD" and "takeoff_complete" in kinds(swarm, sysid),
                     10.0, f"system {sysid} to finish its takeoff")
    await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.HOLD, 5.0,
                "HOLD after takeoff")


# --------------------------------------------------------------------------------- tests
async def test_discovers_ten_vehicles(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(10)
    async with mavsdk_client(swarm.ports.api_port, 10) as systems:
        ids = [await s.get_system_id() for s in systems]
        assert ids == list(range(1, 11))
        for system in systems:
            assert await system.is_connected()
            assert await system.autopilot_type() == Autopilot.PX4
            assert await system.vehicle_type() == Vehicle.MULTICOPTER
            components = await system.component_ids()
            assert 1 in components and CAMERA_COMPONENT_ID in components
        # nothing was moved or armed by discovery alone
        for k in range(1, 11):
            assert not swarm.fleet.autopilots[k - 1].armed
            assert "arm" not in kinds(swarm, k)


async def test_health_all_ok_and_home_on_every_vehicle(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(10)
    async with mavsdk_client(swarm.ports.api_port, 10) as systems:
        telemetries = [TelemetryAsync(s) for s in systems]

        async def all_ok() -> bool:
            for tel in telemetries:
                h = await tel.health()
                if not (h.is_armable and h.is_global_position_ok and h.is_local_position_ok
                        and h.is_home_position_ok):
                    return False
            return True

        await eventually(all_ok, 5.0, "health all ok on 10 vehicles")
        for k, tel in enumerate(telemetries, start=1):
            assert await tel.health_all_ok()
            home = await first(tel.subscribe_home(), lambda h: math.isfinite(h.latitude_deg),
                               5.0, f"home of system {k}")
            hx, hy, hz = swarm.fleet.autopilots[k - 1].home_m
            assert horizontal_error_m(swarm, home.latitude_deg, home.longitude_deg, hx, hy) < 0.1
            assert home.absolute_altitude_m == pytest.approx(geodetic(swarm, hx, hy, hz)[2],
                                                             abs=0.05)


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


async def test_mission_raw_upload_progress_finish_download(swarm_factory,
                                                           mavsdk_client) -> None:
    swarm = await swarm_factory(2)
    async with mavsdk_client(swarm.ports.api_port, 2) as systems:
        sysid = 2  # home at (5, 0)
        system = systems[sysid - 1]
        action, mission = ActionAsync(system), MissionRawAsync(system)
        hx, hy, _ = swarm.fleet.autopilots[sysid - 1].home_m
        points = [(hx + 25.0, hy, 10.0), (hx + 25.0, hy + 25.0, 12.0), (hx, hy + 25.0, 10.0)]
        items = []
        for seq, (x, y, rel) in enumerate(points):
            lat, lon, _ = geodetic(swarm, x, y, 0.0)
            items.append(MissionItem(
                seq=seq, frame=FRAME_GLOBAL_RELATIVE_ALT_INT, command=MAV_CMD_NAV_WAYPOINT,
                current=int(seq == 0), autocontinue=1, param1=0.0, param2=1.0, param3=0.0,
                param4=float("nan"), x=round(lat * 1e7), y=round(lon * 1e7), z=rel,
                mission_type=0,
            ))
        await mission.upload_mission(items)
        ap = swarm.fleet.autopilots[sysid - 1]
        assert ap.mission.total == 3

        downloaded = await mission.download_mission()
        assert len(downloaded) == len(items)
        for sent, got in zip(items, downloaded, strict=True):
            for field in ("seq", "frame", "command", "autocontinue", "x", "y", "mission_type"):
                assert getattr(got, field) == getattr(sent, field), field
            for field in ("param1", "param2", "param3", "param4", "z"):
                a, b = getattr(sent, field), getattr(got, field)
                assert (math.isnan(a) and math.isnan(b)) or a == pytest.approx(b), field
        assert not await mission.is_mission_finished()

        async with watching(mission.subscribe_mission_progress()) as progress:
            await action.set_takeoff_altitude(10.0)
            await action.arm()
            await mission.start_mission()
            await eventually(mission.is_mission_finished, 20.0, "is_mission_finished")
            await progress.wait(lambda p: p.current >= 2, 2.0, "progress on the last item")
        seen = [(p.current, p.total) for p in progress.values]
        assert all(total == 3 for _, total in seen)
        currents = [c for c, _ in seen]
        assert currents == sorted(currents), currents
        assert {1, 2} <= set(currents) and currents[-1] >= 2, currents

        reached = swarm.recorder.events(f"d{sysid}", kinds="mission_item_reached")
        assert [e.data["item"] for e in reached] == [0, 1, 2]
        for event, (x, y, rel) in zip(reached, points, strict=True):
            px, py, pz = swarm.recorder.position_at(f"d{sysid}", event.t_s)
            assert math.hypot(px - x, py - y) <= ap.params["NAV_ACC_RAD"] + 0.1
            assert pz == pytest.approx(rel, abs=ap.params["NAV_ACC_RAD"])
        assert "mission_complete" in kinds(swarm, sysid)
        assert math.dist(truth_pos(swarm, sysid), (hx, hy + 25.0, 10.0)) < 1.0
        assert "arm" not in kinds(swarm, 1)


def _waypoints(swarm: Swarm, points: list[tuple[float, float, float]]) -> list[MissionItem]:
    """NAV_WAYPOINT items, frame 6 (relative altitude), at local ENU (x, y, rel_alt)."""
    items = []
    for seq, (x, y, rel) in enumerate(points):
        lat, lon, _ = geodetic(swarm, x, y, 0.0)
        items.append(MissionItem(seq, FRAME_GLOBAL_RELATIVE_ALT_INT, MAV_CMD_NAV_WAYPOINT,
                                 int(seq == 0), 1, 0.0, 1.0, 0.0, float("nan"),
                                 round(lat * 1e7), round(lon * 1e7), rel, 0))
    return items


async def test_mission_raw_pause_jump_resume_clear(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(1)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        action, mission = ActionAsync(systems[0]), MissionRawAsync(systems[0])
        telemetry = TelemetryAsync(systems[0])
        ap = swarm.fleet.autopilots[0]
        points = [(60.0, 0.0, 10.0), (60.0, 60.0, 10.0), (0.0, 60.0, 10.0)]
        await mission.upload_mission(_waypoints(swarm, points))
        await action.arm()
        await mission.start_mission()
        await eventually(lambda: "mission_item_reached" in kinds(swarm, 1), 10.0, "item 0")
        await mission.pause_mission()  # Hold: brakes on the way to item 1
        await first(telemetry.subscribe_flight_mode(), lambda m: m == FlightMode.HOLD, 3.0,
                    "HOLD on pause")
        await asyncio.sleep(0.2)
        paused_at = truth_pos(swarm, 1)
        await asyncio.sleep(0.3)  # 6 s simulated
        assert math.dist(truth_pos(swarm, 1), paused_at) < 0.2
        # Held short of item 1 (under load the pause may land before it even set off).
        assert 0.0 <= paused_at[1] < 60.0 - ap.params["NAV_ACC_RAD"]
        assert (await mission.mission_progress()).current == 1

        await mission.set_current_mission_item(2)  # skip item 1
        await eventually(lambda: ap.mission.current == 2, 3.0, "current item 2")
        await mission.start_mission()
        await eventually(mission.is_mission_finished, 15.0, "is_mission_finished")
        reached = swarm.recorder.events("d1", kinds="mission_item_reached")
        assert [e.data["item"] for e in reached] == [0, 2]
        assert math.dist(truth_pos(swarm, 1), points[2]) < 1.0

        await mission.clear_mission()
        assert ap.mission.total == 0
        assert await mission.download_mission() == []
        t_refused, here = swarm.fleet.now_s, truth_pos(swarm, 1)
        with pytest.raises(MissionRawError) as refused:  # nothing left to fly
            await mission.start_mission()
        assert refused.value.result == MissionRawResult.DENIED
        await asyncio.sleep(0.2)
        assert math.dist(truth_pos(swarm, 1), here) < 0.2
        assert not swarm.recorder.events("d1", t_refused, kinds="mission_start")


async def test_offboard_position_setpoint_then_stop_holds(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(2)
    async with mavsdk_client(swarm.ports.api_port, 2) as systems:
        sysid = 2
        system = systems[sysid - 1]
        offboard, telemetry = OffboardAsync(system), TelemetryAsync(system)
        ap = swarm.fleet.autopilots[sysid - 1]
        await take_off(swarm, system, sysid, 6.0)
        # local NED about the world origin: 20 m north, 15 m east, 9 m up
        target = (15.0, 20.0, 9.0)
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


async def test_camera_take_photo_geotag(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(2)
    async with mavsdk_client(swarm.ports.api_port, 2) as systems:
        sysid = 2
        system = systems[sysid - 1]
        camera, action = CameraAsync(system), ActionAsync(system)
        await take_off(swarm, system, sysid, 7.0)
        await first(camera.subscribe_camera_list(),
                    lambda cl: any(c.component_id == CAMERA_COMPONENT_ID for c in cl.cameras),
                    5.0, "camera 100 in the camera list")
        infos = []
        async with watching(camera.subscribe_capture_info()) as captures:
            await camera.take_photo(CAMERA_COMPONENT_ID)  # over home (5, 0)
            infos.append(await captures.wait(lambda c: True, 5.0, "first capture_info"))
            lat, lon, alt = geodetic(swarm, 25.0, 20.0, 7.0)
            await action.goto_location(lat, lon, alt, float("nan"))
            await eventually(lambda: math.dist(truth_pos(swarm, sysid), (25.0, 20.0, 7.0)) < 0.3,
                             10.0, "arrival at the second photo point")
            await camera.take_photo(CAMERA_COMPONENT_ID)
            infos.append(await captures.wait(lambda c: c.index != infos[0].index, 5.0,
                                             "second capture_info"))
        photos = swarm.recorder.events(f"d{sysid}", kinds="photo")
        assert len(photos) == 2
        assert photos[1].data["index"] == photos[0].data["index"] + 1
        assert infos[1].index == infos[0].index + 1
        for info, photo, spot in zip(infos, photos, [(5.0, 0.0), (25.0, 20.0)], strict=True):
            px, py, pz = photo.data["position_m"]
            assert math.hypot(px - spot[0], py - spot[1]) < 0.5  # the truth: where it was
            assert pz == pytest.approx(7.0, abs=0.3)
            assert info.is_success
            assert info.index in (photo.data["index"], photo.data["index"] - 1)
            assert horizontal_error_m(swarm, info.position.latitude_deg,
                                      info.position.longitude_deg, px, py) < 0.05
            assert info.position.relative_altitude_m == pytest.approx(pz, abs=0.05)
            assert info.position.absolute_altitude_m == pytest.approx(
                geodetic(swarm, px, py, pz)[2], abs=0.05)
        assert "photo" not in kinds(swarm, 1)


async def test_telemetry_streams_match_truth(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(3)
    async with mavsdk_client(swarm.ports.api_port, 3) as systems:
        sysid = 3  # home (10, 0)
        system = systems[sysid - 1]
        telemetry = TelemetryAsync(system)
        ap = swarm.fleet.autopilots[sysid - 1]
        hx, hy, hz = ap.home_m

        async with watching(
            telemetry.subscribe_position(), telemetry.subscribe_battery(),
            telemetry.subscribe_in_air(), telemetry.subscribe_flight_mode(),
            telemetry.subscribe_home(), telemetry.subscribe_armed(),
        ) as (position, battery, in_air, mode, home, armed):
            # on the ground, disarmed
            p = await position.wait(lambda p: True, 3.0, "position")
            assert horizontal_error_m(swarm, p.latitude_deg, p.longitude_deg, hx, hy) < 0.1
            assert p.relative_altitude_m == pytest.approx(0.0, abs=0.01)
            assert p.absolute_altitude_m == pytest.approx(geodetic(swarm, hx, hy, hz)[2],
                                                          abs=0.01)
            b = await battery.wait(lambda b: True, 3.0, "battery")
            assert b.remaining_percent == pytest.approx(ap.battery_pct, abs=1.0)
            n_cells = ap.params["BAT_N_CELLS"]
            assert 3.5 * n_cells <= b.voltage_v <= 4.2 * n_cells + 0.01
            assert await in_air.wait(lambda v: True, 3.0, "in_air") is False
            assert await armed.wait(lambda v: True, 3.0, "armed") is False
            assert await mode.wait(lambda v: True, 3.0, "flight mode") == FlightMode.HOLD
            h = await home.wait(lambda h: math.isfinite(h.latitude_deg), 3.0, "home")
            assert horizontal_error_m(swarm, h.latitude_deg, h.longitude_deg, hx, hy) < 0.1

            # in the air: every stream follows
            await take_off(swarm, system, sysid, 10.0)
            assert ap.in_air and ap.armed
            await armed.wait(lambda v: v, 3.0, "armed True")
            await in_air.wait(lambda v: v, 3.0, "in_air True")
            p = await position.wait(lambda p: abs(p.relative_altitude_m - 10.0) < 0.2, 3.0,
                                    "hovering at 10 m")
            x, y, z = truth_pos(swarm, sysid)
            assert horizontal_error_m(swarm, p.latitude_deg, p.longitude_deg, x, y) < 0.2
            assert p.absolute_altitude_m == pytest.approx(geodetic(swarm, x, y, z)[2], abs=0.2)
            # hovering drains the battery; telemetry reports the drained value
            start_pct = ap.battery_pct
            await eventually(lambda: ap.battery_pct < start_pct - 2.0, 10.0, "2 % drained")
            b = await battery.wait(lambda b: b.remaining_percent < start_pct - 1.0, 5.0,
                                   "battery telemetry drop")
            assert b.remaining_percent == pytest.approx(ap.battery_pct, abs=2.0)
            assert b.remaining_percent < 100.0
            # the home position stays where the vehicle took off
            h = home.values[-1]
            assert horizontal_error_m(swarm, h.latitude_deg, h.longitude_deg, hx, hy) < 0.1


async def test_command_to_unknown_system_is_ignored(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(3)
    async with mavsdk_client(swarm.ports.api_port, 3) as systems:
        _, swarm_port = swarm.endpoints[0].local_address
        sniffer = mavlink.MAVLink(None, srcSystem=201, srcComponent=190)
        sniffer.robust_parsing = True
        loop = asyncio.get_running_loop()
        received: list[Any] = []

        class Peer(asyncio.DatagramProtocol):
            def datagram_received(self, data: bytes, addr: Any) -> None:
                received.extend(sniffer.parse_buffer(data) or [])

        transport, _ = await loop.create_datagram_endpoint(
            Peer, local_addr=("127.0.0.1", 0), remote_addr=("127.0.0.1", swarm_port))
        try:
            unroutable = swarm.endpoints[0].stats.unroutable
            for _ in range(3):  # ARM, TAKEOFF to system 42, which does not exist
                transport.sendto(mavlink.MAVLink_command_long_message(
                    42, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0).pack(sniffer))
                transport.sendto(mavlink.MAVLink_command_long_message(
                    42, 1, 22, 0, 0, 0, 0, 0, 0, 0, 0).pack(sniffer))
            await asyncio.sleep(1.2)
            assert received, "the swarm should stream to a peer that talked to it"
            assert swarm.endpoints[0].stats.unroutable >= unroutable + 6
            acks = [m for m in received if m.get_type() == "COMMAND_ACK"
                    and m.target_system == 201]
            assert acks == []
            assert 42 not in {m.get_srcSystem() for m in received}
            for k in range(1, 4):
                assert not swarm.fleet.autopilots[k - 1].armed
                assert "arm" not in kinds(swarm, k)

            # the others are undisturbed: still connected, still obey MAVSDK
            for system in systems:
                assert await system.is_connected()
            await ActionAsync(systems[1]).arm()
            assert swarm.fleet.autopilots[1].armed
            assert not swarm.fleet.autopilots[0].armed and not swarm.fleet.autopilots[2].armed
        finally:
            transport.close()


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
        await mission.upload_mission(_waypoints(swarm, [(60.0, 0.0, 10.0), (60.0, 60.0, 10.0)]))
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
    swarm = await swarm_factory(1)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        action, telemetry = ActionAsync(systems[0]), TelemetryAsync(systems[0])
        await take_off(swarm, systems[0], 1, 6.0)
        await action.land()
        await eventually(lambda: truth_pos(swarm, 1)[2] < 3.0, 10.0, "final descent")
        await action.hold()
        await asyncio.sleep(0.2)  # 4 s simulated: braked and hovering
        assert swarm.fleet.autopilots[0].in_air
        z = truth_pos(swarm, 1)[2]
        assert z > 0.5
        states = await _landed_states_after(telemetry, swarm, swarm.fleet.now_s, 4.0)
        assert truth_pos(swarm, 1)[2] == pytest.approx(z, abs=0.1)  # still hovering
        assert states and all(s == LandedState.IN_AIR for s in states), states
