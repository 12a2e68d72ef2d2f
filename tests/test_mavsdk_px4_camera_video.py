"""PX4 conformance through the real MAVSDK client (native binding) over UDP: the camera
plugin's video mode, recording (with its storage and capture status) and video stream on
camera component 100, checked against the ground truth."""

from __future__ import annotations

import pytest
from mavsdk.asyncio.plugins.camera import CameraAsync
from mavsdk.plugins.camera import CameraError, CameraResult, Mode, VideoStreamInfo

from tests.mavsdk_helpers import (
    CAMERA_COMPONENT_ID,
    eventually,
    first,
    take_off,
    truth_pos,
    watching,
)

pytestmark = pytest.mark.mavsdk


async def _mode_is(camera: CameraAsync, mode: Mode) -> bool:
    return await camera.get_mode(CAMERA_COMPONENT_ID) == mode


async def test_camera_video_example_records_and_streams(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(1, speed=5.0)
    async with mavsdk_client(swarm.ports.api_port, 1) as systems:
        camera = CameraAsync(systems[0])
        await first(camera.subscribe_camera_list(),
                    lambda cl: any(c.component_id == CAMERA_COMPONENT_ID for c in cl.cameras),
                    5.0, "camera 100 in the camera list")
        await take_off(swarm, systems[0], 1, 8.0)
        await eventually(
            lambda: _mode_is(camera, Mode.PHOTO), 5.0, "photo mode from CAMERA_SETTINGS")
        with pytest.raises(CameraError) as refused:  # still in photo mode
            await camera.start_video(CAMERA_COMPONENT_ID)
        assert refused.value.result == CameraResult.DENIED
        async with watching(camera.subscribe_storage(),
                            camera.subscribe_video_stream_info()) as (storage, streams):
            # (MAVSDK announces a mode change to subscribe_mode only for cameras with a
            # camera definition file; get_mode reads it)
            await camera.set_mode(CAMERA_COMPONENT_ID, Mode.VIDEO)
            assert await camera.get_mode(CAMERA_COMPONENT_ID) == Mode.VIDEO
            assert swarm.links[0].camera.video.mode == 1
            await camera.start_video(CAMERA_COMPONENT_ID)
            started = swarm.fleet.now_s
            recording = await storage.wait(
                lambda u: u.storage.video_on and u.storage.recording_time_s > 5.0, 10.0,
                "a recording over 5 s in the storage updates")
            assert recording.component_id == CAMERA_COMPONENT_ID
            assert recording.storage.recording_time_s <= swarm.fleet.now_s - started + 0.1
            await camera.stop_video(CAMERA_COMPONENT_ID)
            stopped = await storage.wait(
                lambda u: not u.storage.video_on and u.storage.available_storage_mib
                < u.storage.total_storage_mib, 10.0, "the recording stopped, its storage used")
            assert stopped.storage.recording_time_s == 0.0
            await camera.start_video_streaming(CAMERA_COMPONENT_ID, 1)
            running = await streams.wait(
                lambda u: u.video_stream_info.status
                == VideoStreamInfo.VideoStreamStatus.IN_PROGRESS, 5.0, "the stream running")
            settings = running.video_stream_info.settings
            assert (settings.horizontal_resolution_pix, settings.vertical_resolution_pix) == (
                1920, 1080)
            await camera.stop_video_streaming(CAMERA_COMPONENT_ID, 1)
            seen = len(streams.values)
            await streams.wait(lambda u: u in streams.values[seen:] and u.video_stream_info.status
                               == VideoStreamInfo.VideoStreamStatus.NOT_RUNNING, 5.0,
                               "the stream stopped")
        events = swarm.recorder.events("d1", kinds=("video_start", "video_stop"))
        assert [e.kind for e in events] == ["video_start", "video_stop"]
        assert events[0].data["position_m"] == pytest.approx(list(truth_pos(swarm, 1)), abs=0.1)
        assert events[1].data["duration_s"] > 5.0
