"""PX4 conformance in memory: the camera component's modes, video recording with its capture
status, storage and the video stream; refusals change nothing."""

from __future__ import annotations

import math

import pytest

from emulator.mavlink.camera_video import STORAGE_TOTAL_MIB, VIDEO_BITRATE_B_S
from mavlink_vocabulary import MavCmd, MavComponent, MavResult
from tests.memory_link import MemoryLink

CAMERA = MavComponent.CAMERA
NAN = math.nan


def _camera(link: MemoryLink, command: int, *params: float):
    return link.command_long(1, command, *params, component=CAMERA)


def _statuses(link: MemoryLink, since: int):
    return link.messages("CAMERA_CAPTURE_STATUS", system=1, since=since)


def test_video_is_recorded_in_video_mode_with_its_capture_status() -> None:
    link = MemoryLink(1, telemetry=False)
    link.arm_and_take_off(1, 10.0)
    ap = link.fleet.autopilots[0]
    since = len(link.received)
    ack = _camera(link, MavCmd.VIDEO_START_CAPTURE, 0, 1)
    assert ack.result == MavResult.DENIED  # image mode
    texts = [m.text for m in link.messages("STATUSTEXT", since=since)]
    assert texts == ["Camera: video capture needs video mode"]
    since = len(link.received)
    assert _camera(link, MavCmd.SET_CAMERA_MODE, 0, 1).result == MavResult.ACCEPTED
    [settings] = link.messages("CAMERA_SETTINGS", since=since)
    assert settings.mode_id == 1 and settings.get_srcComponent() == CAMERA
    # start with the status at 2 Hz (wall): recording time in simulated seconds
    since = len(link.received)
    t0 = link.fleet.now_s
    assert _camera(link, MavCmd.VIDEO_START_CAPTURE, 0, 2).result == MavResult.ACCEPTED
    link.advance(3.1)
    statuses = _statuses(link, since)
    assert len(statuses) == 1 + 6  # the answer, then 2 Hz for 3 s
    assert all(s.video_status == 1 for s in statuses)
    times = [s.recording_time_ms for s in statuses]
    assert times == sorted(times) and times[-1] == pytest.approx(3000, abs=30)
    # a repeated start (a retransmission) records on; a mode change waits for the stop
    assert _camera(link, MavCmd.VIDEO_START_CAPTURE, 0, 2).result == MavResult.ACCEPTED
    assert _camera(link, MavCmd.SET_CAMERA_MODE, 0, 0).result == MavResult.DENIED
    # photos are taken in video mode too
    assert _camera(link, MavCmd.IMAGE_START_CAPTURE, 0, 0, 1, 1).result == MavResult.ACCEPTED
    link.advance(1.9)
    since = len(link.received)
    assert _camera(link, MavCmd.VIDEO_STOP_CAPTURE, 0).result == MavResult.ACCEPTED
    [stopped] = _statuses(link, since)
    assert stopped.video_status == 0 and stopped.image_count == ap.photo_count == 1
    link.advance(2.0)
    assert len(_statuses(link, since)) == 1  # no status after the stop
    starts = link.fleet.recorder.events("d1", kinds=("video_start", "video_stop"))
    assert [e.kind for e in starts] == ["video_start", "video_stop"]
    assert starts[0].t_s == pytest.approx(t0, abs=0.05)
    duration = starts[1].data["duration_s"]
    assert duration == pytest.approx(5.0, abs=0.1)
    assert starts[0].data["position_m"] == pytest.approx(list(ap.position_m), abs=0.01)
    # the storage the video took
    since = len(link.received)
    assert _camera(link, MavCmd.REQUEST_MESSAGE, 261).result == MavResult.ACCEPTED
    [storage] = link.messages("STORAGE_INFORMATION", since=since)
    used = duration * VIDEO_BITRATE_B_S / 8 / 2**20
    assert storage.used_capacity == pytest.approx(used, rel=1e-4)
    assert storage.available_capacity == pytest.approx(STORAGE_TOTAL_MIB - used, rel=1e-6)
    assert stopped.available_capacity == pytest.approx(STORAGE_TOTAL_MIB - used, rel=1e-6)


def test_the_video_stream_is_described_started_and_stopped() -> None:
    link = MemoryLink(1, telemetry=False)
    since = len(link.received)
    assert _camera(link, MavCmd.REQUEST_MESSAGE, 259).result == MavResult.ACCEPTED
    [info] = link.messages("CAMERA_INFORMATION", since=since)
    assert info.flags & 1 and info.flags & 2 and info.flags & 4 and info.flags & 256
    for command, running in ((MavCmd.VIDEO_START_STREAMING, 1), (MavCmd.VIDEO_STOP_STREAMING, 0)):
        since = len(link.received)
        assert _camera(link, command, 1).result == MavResult.ACCEPTED
        [described] = link.messages("VIDEO_STREAM_INFORMATION", since=since)
        [status] = link.messages("VIDEO_STREAM_STATUS", since=since)
        assert described.stream_id == status.stream_id == 1 and described.count == 1
        assert described.flags == status.flags == running
        assert (status.resolution_h, status.resolution_v) == (1920, 1080)
    since = len(link.received)
    assert _camera(link, MavCmd.REQUEST_VIDEO_STREAM_STATUS, 1).result == MavResult.ACCEPTED
    assert link.messages("VIDEO_STREAM_STATUS", since=since)[0].flags == 0


def test_bad_camera_commands_are_denied_and_change_nothing() -> None:
    link = MemoryLink(1, telemetry=False)
    camera = link.swarm.links[0].camera.video
    for command, params in ((MavCmd.SET_CAMERA_MODE, (0, 2)),  # no such mode
                            (MavCmd.VIDEO_START_STREAMING, (7,)),  # no such stream
                            (MavCmd.VIDEO_STOP_CAPTURE, (3,))):
        assert _camera(link, command, *params).result == MavResult.DENIED, command
    assert _camera(link, MavCmd.SET_CAMERA_MODE, NAN, 1).result == MavResult.ACCEPTED
    for params in ((0, -1), (0, 1000), (2, 1)):  # bad status rates, a stream that is not
        assert _camera(link, MavCmd.VIDEO_START_CAPTURE, *params).result == MavResult.DENIED
    assert camera.recording_since_s is None and not camera.streaming
    assert not link.fleet.recorder.events("d1", kinds=("video_start", "video_stop"))
