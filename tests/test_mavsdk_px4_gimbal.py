"""PX4 conformance through the real MAVSDK client (native binding) over UDP: the gimbal plugin
(gimbal protocol v2) finds the gimbal of the vehicle whose scenario asks for one, takes
control and aims it; the gimbal's truth and the attitude MAVSDK reads agree."""

from __future__ import annotations

import dataclasses

import pytest
from mavsdk.asyncio.plugins.gimbal import GimbalAsync
from mavsdk.plugins.gimbal import ControlMode, GimbalMode, SendMode

from emulator.scenario import default_scenario
from tests.mavsdk_helpers import eventually, first

pytestmark = pytest.mark.mavsdk


async def test_gimbal_example_takes_control_and_aims(swarm_factory, mavsdk_client) -> None:
    scenario = default_scenario(2)
    with_gimbal = dataclasses.replace(scenario.vehicles[1], gimbal=True)  # only on d2
    swarm = await swarm_factory(2, speed=5.0, scenario=dataclasses.replace(
        scenario, vehicles=(scenario.vehicles[0], with_gimbal)))
    async with mavsdk_client(swarm.ports.api_port, 2) as systems:
        gimbal = GimbalAsync(systems[1])
        found = await first(gimbal.subscribe_gimbal_list(), lambda gl: len(gl.gimbals) > 0, 10.0,
                            "the gimbal in the gimbal list")
        [item] = found.gimbals
        assert (item.gimbal_manager_component_id, item.gimbal_device_id) == (1, 154)
        assert (item.vendor_name, item.model_name) == ("mavswarm", "gimbal")
        await gimbal.take_control(item.gimbal_id, ControlMode.PRIMARY)

        async def in_control() -> bool:  # from the next GIMBAL_MANAGER_STATUS on
            control = await gimbal.get_control_status(item.gimbal_id)
            return bool(control.control_mode == ControlMode.PRIMARY)

        await eventually(in_control, 5.0, "MAVSDK reading primary control")
        await gimbal.set_angles(item.gimbal_id, 0.0, -45.0, 20.0, GimbalMode.YAW_FOLLOW,
                                SendMode.ONCE)
        truth = swarm.links[1].gimbal
        await eventually(lambda: (truth.pitch_deg, truth.yaw_deg) == (-45.0, 20.0), 5.0,
                         "the gimbal at pitch -45, yaw 20")

        async def reads_aimed() -> bool:
            forward = (await gimbal.get_attitude(item.gimbal_id)).euler_angle_forward
            return abs(forward.pitch_deg + 45.0) < 0.1 and abs(forward.yaw_deg - 20.0) < 0.1

        await eventually(reads_aimed, 5.0, "MAVSDK reading the aimed attitude")
        [event] = swarm.recorder.events("d2", kinds="gimbal")
        assert (event.data["pitch_deg"], event.data["yaw_deg"]) == (-45.0, 20.0)
        await gimbal.release_control(item.gimbal_id)
        await eventually(lambda: truth.primary == (0, 0), 5.0, "control released")
        assert swarm.links[0].gimbal is None  # d1 has none
