"""The camera component (MAVLink component 100) of one vehicle: the camera protocol.

Photos in either camera mode; video mode, recording and the video stream in
emulator.mavlink.camera_video. Nothing here sends: command handling returns a `Reply`, the
other methods build messages that the vehicle link sends as the camera component.
"""

from __future__ import annotations

import math

from emulator.flight.autopilot import Autopilot, ImageCapture
from emulator.mavlink.camera_video import STORAGE_TOTAL_MIB, VIDEO_COMMANDS, VideoCapture
from emulator.mavlink.codec import mavlink
from emulator.mavlink.command_args import CommandArgs
from emulator.mavlink.messages import component_heartbeat
from emulator.mavlink.reply import Action, Reply, SendMessage, SendOnce
from mavlink_vocabulary import (
    CameraCapFlags,
    MavAutopilot,
    MavCmd,
    MavComponent,
    MavResult,
    MavType,
    MessageId,
)

__all__ = ["CAMERA_COMMANDS", "CAMERA_COMPONENT_ID", "CAMERA_MESSAGES", "MAV_AUTOPILOT_INVALID",
           "MAV_TYPE_CAMERA", "CameraComponent"]

CAMERA_COMPONENT_ID = MavComponent.CAMERA
MAV_TYPE_CAMERA = MavType.CAMERA
MAV_AUTOPILOT_INVALID = MavAutopilot.INVALID
CAMERA_MESSAGES = frozenset({
    MessageId.CAMERA_INFORMATION, MessageId.CAMERA_SETTINGS, MessageId.STORAGE_INFORMATION,
    MessageId.CAMERA_CAPTURE_STATUS, MessageId.VIDEO_STREAM_INFORMATION,
    MessageId.VIDEO_STREAM_STATUS,
})
_FLAGS = (CameraCapFlags.CAPTURE_VIDEO | CameraCapFlags.CAPTURE_IMAGE | CameraCapFlags.HAS_MODES
          | CameraCapFlags.CAN_CAPTURE_IMAGE_IN_VIDEO_MODE | CameraCapFlags.HAS_VIDEO_STREAM)
# the legacy camera requests: the message each asks for
_REQUESTS = {
    MavCmd.REQUEST_CAMERA_INFORMATION: MessageId.CAMERA_INFORMATION,
    MavCmd.REQUEST_CAMERA_SETTINGS: MessageId.CAMERA_SETTINGS,
    MavCmd.REQUEST_STORAGE_INFORMATION: MessageId.STORAGE_INFORMATION,
    MavCmd.REQUEST_CAMERA_CAPTURE_STATUS: MessageId.CAMERA_CAPTURE_STATUS,
    MavCmd.REQUEST_VIDEO_STREAM_INFORMATION: MessageId.VIDEO_STREAM_INFORMATION,
    MavCmd.REQUEST_VIDEO_STREAM_STATUS: MessageId.VIDEO_STREAM_STATUS,
}
# what the camera component answers (anything else addressed to it is unsupported)
CAMERA_COMMANDS = frozenset({
    MavCmd.IMAGE_START_CAPTURE, MavCmd.IMAGE_STOP_CAPTURE, MavCmd.REQUEST_MESSAGE, *_REQUESTS,
    *VIDEO_COMMANDS,
})


def _fixed(text: str, size: int) -> list[int]:
    raw = list(text.encode("ascii"))[:size]
    return raw + [0] * (size - len(raw))


class CameraComponent:
    """A nadir camera: one still capture per IMAGE_START_CAPTURE, geotagged; video.

    A single capture may carry a capture sequence number (param 4, from 1): a command that
    repeats the last sequence number is a retransmission, so it takes no second photo and the
    camera sends that photo's CAMERA_IMAGE_CAPTURED again (its first copy may have been lost)."""

    def __init__(self) -> None:
        self._last_sequence = 0.0
        self._last_captured: mavlink.MAVLink_message | None = None
        self.video = VideoCapture()

    @staticmethod
    def heartbeat(ap: Autopilot) -> mavlink.MAVLink_message:
        return component_heartbeat(ap, MavType.CAMERA)

    def build(self, ap: Autopilot, msg_id: int) -> mavlink.MAVLink_message | None:
        t_ms = int(ap.now_s * 1000.0) & 0xFFFFFFFF
        video = self.video
        if msg_id == MessageId.CAMERA_INFORMATION:
            return mavlink.MAVLink_camera_information_message(
                t_ms, _fixed("mavswarm", 32), _fixed("nadir", 32), 1, 4.5, 6.17, 4.55,
                4000, 3000, 0, _FLAGS, 0, b"",
            )
        if msg_id == MessageId.CAMERA_SETTINGS:
            return mavlink.MAVLink_camera_settings_message(t_ms, video.mode, math.nan, math.nan)
        if msg_id == MessageId.STORAGE_INFORMATION:
            used = video.used_mib(ap)
            return mavlink.MAVLink_storage_information_message(
                t_ms, 1, 1, 2, STORAGE_TOTAL_MIB, used, STORAGE_TOTAL_MIB - used, 90.0, 60.0
            )
        if msg_id == MessageId.CAMERA_CAPTURE_STATUS:
            return video.capture_status(ap, t_ms)
        if msg_id == MessageId.VIDEO_STREAM_INFORMATION:
            return video.stream_information()
        if msg_id == MessageId.VIDEO_STREAM_STATUS:
            return video.stream_status()
        return None

    def handle_command(self, ap: Autopilot, a: CommandArgs, wall_now_s: float) -> Reply:
        if a.command == MavCmd.IMAGE_START_CAPTURE:  # p2 interval, p3 total images
            total = a.p3 if math.isfinite(a.p3) else 1.0
            if total != 1.0:
                return Reply.denied("Camera: only single captures (total images = 1)")
            sequence = a.p4 if math.isfinite(a.p4) and a.p4 >= 1.0 else 0.0
            if sequence and sequence == self._last_sequence:
                captured = self._last_captured
                if captured is None:
                    return Reply.accepted()
                return Reply.accepted(SendMessage(captured, MavComponent.CAMERA))
            self._last_sequence = sequence
            return Reply.accepted(Action(ap.take_photo))
        if a.command == MavCmd.IMAGE_STOP_CAPTURE:
            return Reply.accepted()
        if a.command in VIDEO_COMMANDS:
            return self.video.handle_command(ap, a, wall_now_s)
        requested = _REQUESTS.get(MavCmd(a.command)) if a.command in _REQUESTS else None
        if requested is None:
            return Reply(MavResult.UNSUPPORTED)
        return Reply.accepted(SendOnce(requested))

    def image_captured(self, ap: Autopilot, capture: ImageCapture) -> mavlink.MAVLink_message:
        """The CAMERA_IMAGE_CAPTURED of a photo just taken (kept for a retransmission)."""
        origin = ap.fleet.world.origin
        lat, lon, alt = origin.to_geodetic(*capture.position_m)
        yaw = math.radians(capture.yaw_deg)
        q = [math.cos(yaw / 2.0), 0.0, 0.0, math.sin(yaw / 2.0)]
        rel_mm = round((capture.position_m[2] - ap.home_m[2]) * 1000.0)
        self._last_captured = mavlink.MAVLink_camera_image_captured_message(
            int(capture.t_s * 1000.0), 0, 0, round(lat * 1e7), round(lon * 1e7),
            round(alt * 1000.0), rel_mm, q, capture.index, 1,
            f"mavswarm://{ap.vehicle_id}/image_{capture.index:04d}.jpg".encode(),
        )
        return self._last_captured
