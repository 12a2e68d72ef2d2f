"""The camera component's video side: camera mode, recording and the video stream.

Recording (VIDEO_START_CAPTURE / VIDEO_STOP_CAPTURE) needs video mode (SET_CAMERA_MODE 1),
as a real camera's, and lasts in simulated time: CAMERA_CAPTURE_STATUS reports the recording
time and the storage the video has taken (VIDEO_BITRATE_B_S), at the frequency the start
command asks for (wall-clock Hz, as every stream) until the recording stops. The one video
stream (VIDEO_STREAM_INFORMATION / _STATUS) is started and stopped by
VIDEO_START_STREAMING / _STOP_STREAMING; it is described, not served: no media flows. Start
and stop are ground-truth events with the vehicle's position.
"""

from __future__ import annotations

import math
from enum import IntEnum

from emulator.flight.autopilot import Autopilot
from emulator.mavlink.codec import mavlink
from emulator.mavlink.command_args import CommandArgs
from emulator.mavlink.reply import Reply, SendOnce
from emulator.truth_events import TruthEventKind
from mavlink_vocabulary import MavCmd, MessageId

__all__ = ["STORAGE_TOTAL_MIB", "VIDEO_BITRATE_B_S", "VIDEO_COMMANDS", "CameraMode",
           "VideoCapture"]

STREAM_ID = 1
VIDEO_BITRATE_B_S = 8_000_000
VIDEO_FRAMERATE_HZ = 30.0
VIDEO_RESOLUTION = (1920, 1080)
VIDEO_HFOV_DEG = 90
STORAGE_TOTAL_MIB = 65536.0
VIDEO_STREAM_TYPE_RTSP = 0
VIDEO_STREAM_STATUS_FLAGS_RUNNING = 1
MAX_STATUS_HZ = 50.0
VIDEO_COMMANDS = frozenset({
    MavCmd.SET_CAMERA_MODE, MavCmd.VIDEO_START_CAPTURE, MavCmd.VIDEO_STOP_CAPTURE,
    MavCmd.VIDEO_START_STREAMING, MavCmd.VIDEO_STOP_STREAMING,
})


class CameraMode(IntEnum):
    """CAMERA_MODE_*."""

    IMAGE = 0
    VIDEO = 1


def _stream_id_ok(value: float) -> bool:
    """A command's stream id: unset (NaN), 0 (all streams) or the one stream."""
    return not math.isfinite(value) or value in (0.0, float(STREAM_ID))


class VideoCapture:
    """Mode, recording and stream state of one vehicle's camera."""

    def __init__(self) -> None:
        self.mode = CameraMode.IMAGE
        self.recording_since_s: float | None = None  # simulated time
        self.recorded_s = 0.0  # finished recordings, simulated seconds
        self.streaming = False
        self._status_interval_s: float | None = None  # wall seconds
        self.status_due_wall_s: float | None = None

    def recording_s(self, ap: Autopilot) -> float:
        since = self.recording_since_s
        return 0.0 if since is None else ap.now_s - since

    def used_mib(self, ap: Autopilot) -> float:
        seconds = self.recorded_s + self.recording_s(ap)
        return seconds * VIDEO_BITRATE_B_S / 8.0 / 2.0**20

    def handle_command(self, ap: Autopilot, a: CommandArgs, wall_now_s: float) -> Reply:
        if a.command == MavCmd.SET_CAMERA_MODE:
            return self._set_mode(a.p2)
        if a.command == MavCmd.VIDEO_START_CAPTURE:
            return self._start(ap, a, wall_now_s)
        if a.command == MavCmd.VIDEO_STOP_CAPTURE:
            return self._stop(ap, a)
        if not _stream_id_ok(a.p1):
            return Reply.denied(f"Camera: no video stream {a.p1:g}")
        self.streaming = a.command == MavCmd.VIDEO_START_STREAMING
        return Reply.accepted(SendOnce(MessageId.VIDEO_STREAM_INFORMATION),
                              SendOnce(MessageId.VIDEO_STREAM_STATUS))

    def _set_mode(self, value: float) -> Reply:
        mode = value if math.isfinite(value) else 0.0
        if mode not in tuple(CameraMode):
            return Reply.denied(f"Camera: unknown mode {mode:g}")
        if self.recording_since_s is not None and mode != CameraMode.VIDEO:
            return Reply.denied("Camera: mode change refused while recording")
        self.mode = CameraMode(int(mode))
        return Reply.accepted(SendOnce(MessageId.CAMERA_SETTINGS))

    def _start(self, ap: Autopilot, a: CommandArgs, wall_now_s: float) -> Reply:
        if not _stream_id_ok(a.p1):
            return Reply.denied(f"Camera: no video stream {a.p1:g}")
        if self.mode is not CameraMode.VIDEO:
            return Reply.denied("Camera: video capture needs video mode")
        hz = a.p2 if math.isfinite(a.p2) else 0.0
        if not 0.0 <= hz <= MAX_STATUS_HZ:
            return Reply.denied(f"Camera: status rate {hz:g} Hz not in [0, {MAX_STATUS_HZ:g}]")
        self._status_interval_s = 1.0 / hz if hz > 0.0 else None
        self.status_due_wall_s = None if hz == 0.0 else wall_now_s + 1.0 / hz
        if self.recording_since_s is None:  # a repeated start records on
            self.recording_since_s = ap.now_s
            ap.event(TruthEventKind.VIDEO_START, position_m=list(ap.position_m))
        return Reply.accepted(SendOnce(MessageId.CAMERA_CAPTURE_STATUS))

    def _stop(self, ap: Autopilot, a: CommandArgs) -> Reply:
        if not _stream_id_ok(a.p1):
            return Reply.denied(f"Camera: no video stream {a.p1:g}")
        if self.recording_since_s is not None:
            duration_s = self.recording_s(ap)
            self.recorded_s += duration_s
            self.recording_since_s = None
            ap.event(TruthEventKind.VIDEO_STOP, position_m=list(ap.position_m),
                     duration_s=duration_s)
        self._status_interval_s = self.status_due_wall_s = None
        return Reply.accepted(SendOnce(MessageId.CAMERA_CAPTURE_STATUS))

    def status_due(self, wall_now_s: float) -> bool:
        """Whether a CAMERA_CAPTURE_STATUS of the recording is due now (then the next one is
        scheduled)."""
        due, interval = self.status_due_wall_s, self._status_interval_s
        if due is None or interval is None or wall_now_s < due:
            return False
        self.status_due_wall_s = max(due + interval, wall_now_s)
        return True

    def capture_status(self, ap: Autopilot, t_ms: int) -> mavlink.MAVLink_message:
        video_on = int(self.recording_since_s is not None)
        return mavlink.MAVLink_camera_capture_status_message(
            t_ms, 0, video_on, 0.0, round(self.recording_s(ap) * 1000.0),
            STORAGE_TOTAL_MIB - self.used_mib(ap), ap.photo_count)

    def stream_information(self) -> mavlink.MAVLink_message:
        w, h = VIDEO_RESOLUTION
        return mavlink.MAVLink_video_stream_information_message(
            STREAM_ID, 1, VIDEO_STREAM_TYPE_RTSP, self._stream_flags(), VIDEO_FRAMERATE_HZ, w, h,
            VIDEO_BITRATE_B_S, 0, VIDEO_HFOV_DEG, b"nadir", b"")

    def stream_status(self) -> mavlink.MAVLink_message:
        w, h = VIDEO_RESOLUTION
        return mavlink.MAVLink_video_stream_status_message(
            STREAM_ID, self._stream_flags(), VIDEO_FRAMERATE_HZ, w, h, VIDEO_BITRATE_B_S, 0,
            VIDEO_HFOV_DEG)

    def _stream_flags(self) -> int:
        return VIDEO_STREAM_STATUS_FLAGS_RUNNING if self.streaming else 0
