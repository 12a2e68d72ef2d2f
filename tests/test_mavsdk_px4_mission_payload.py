"""The native MAVSDK mission plugin's gimbal and camera actions (the MAVSDK mission example):
the plan, with its DO_GIMBAL_MANAGER_* and camera items, is accepted and flown, and the
photo it asks for is taken; checked against the ground truth."""

from __future__ import annotations

import pytest
from mavsdk.asyncio.plugins.mission import MissionAsync
from mavsdk.asyncio.plugins.mission_raw import MissionRawAsync
from mavsdk.plugins.mission import MissionItem, MissionPlan

from tests.mavsdk_helpers import eventually, geodetic, kinds, take_off

pytestmark = pytest.mark.mavsdk


def _item(swarm, x: float, y: float, *, pitch: float, action: MissionItem.CameraAction
          ) -> MissionItem:
    lat, lon, _ = geodetic(swarm, x, y, 0.0)
    return MissionItem(lat, lon, 12.0, 6.0, True, pitch, 0.0, action, float("nan"),
                       float("nan"), float("nan"), float("nan"), float("nan"),
                       MissionItem.VehicleAction.NONE)


async def test_mission_with_gimbal_and_camera_actions_is_flown(swarm_factory,
                                                                mavsdk_client) -> None:
    swarm = await swarm_factory(1, speed=10.0)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        system = systems[0]
        mission = MissionAsync(system)
        plan = MissionPlan([
            _item(swarm, 0.0, 30.0, pitch=-45.0, action=MissionItem.CameraAction.TAKE_PHOTO),
            _item(swarm, 30.0, 30.0, pitch=-90.0, action=MissionItem.CameraAction.START_VIDEO),
            _item(swarm, 30.0, 0.0, pitch=0.0, action=MissionItem.CameraAction.STOP_VIDEO),
        ])
        await mission.upload_mission(plan)
        commands = {it.command for it in await MissionRawAsync(system).download_mission()}
        assert 1000 in commands  # DO_GIMBAL_MANAGER_PITCHYAW, stored as uploaded
        await take_off(swarm, system, 1, 10.0)
        await mission.start_mission()
        await eventually(mission.is_mission_finished, 30.0, "the mission finished")
        assert kinds(swarm, 1).count("photo") == 1
        reached = [e.data["item"] for e in swarm.recorder.events("d1",
                                                                 kinds="mission_item_reached")]
        assert reached == sorted(reached) and reached
