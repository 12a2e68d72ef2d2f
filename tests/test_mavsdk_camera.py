"""The camera component through MAVSDK's camera plugin: a photo and its geotag.

The real MAVSDK client (native binding) over UDP on 127.0.0.1, checked against the ground
truth."""

from __future__ import annotations

import math

import pytest
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.camera import CameraAsync

from tests.mavsdk_helpers import (
    CAMERA_COMPONENT_ID,
    eventually,
    first,
    geodetic,
    horizontal_error_m,
    kinds,
    take_off,
    truth_pos,
    watching,
)

pytestmark = pytest.mark.mavsdk


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
