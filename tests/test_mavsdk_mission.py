"""Missions through MAVSDK's mission_raw plugin: upload, progress, finish, download, pause,
jump, resume and clear.

The real MAVSDK client (native binding) over UDP on 127.0.0.1, checked against the ground
truth."""

from __future__ import annotations

import asyncio
import math

import pytest
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.mission_raw import MissionRawAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync
from mavsdk.plugins.mission_raw import MissionItem, MissionRawError, MissionRawResult
from mavsdk.plugins.telemetry import FlightMode

from tests.mavsdk_helpers import (
    FRAME_GLOBAL_RELATIVE_ALT_INT,
    MAV_CMD_NAV_WAYPOINT,
    eventually,
    first,
    geodetic,
    kinds,
    truth_pos,
    watching,
    waypoints_items,
)

pytestmark = pytest.mark.mavsdk


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

async def test_mission_raw_pause_jump_resume_clear(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(1)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        action, mission = ActionAsync(systems[0]), MissionRawAsync(systems[0])
        telemetry = TelemetryAsync(systems[0])
        ap = swarm.fleet.autopilots[0]
        points = [(60.0, 0.0, 10.0), (60.0, 60.0, 10.0), (0.0, 60.0, 10.0)]
        await mission.upload_mission(waypoints_items(swarm, points))
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
