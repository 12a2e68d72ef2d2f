"""The camera component (MAVLink component 100) of one vehicle: the camera protocol."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from emulator.flight.autopilot import ImageCapture
from emulator.mavlink.codec import mavlink

if TYPE_CHECKING:
    from emulator.mavlink.commands import CommandArgs
    from emulator.mavlink.vehicle_link import VehicleLink

__all__ = ["CAMERA_COMPONENT_ID", "CameraComponent"]

CAMERA_COMPONENT_ID = 100
MAV_TYPE_CAMERA = 30
MAV_AUTOPILOT_INVALID = 8
_CAP_CAPTURE_IMAGE = 2
_MSG_CAMERA_INFORMATION = 259
_MSG_CAMERA_SETTINGS = 260
_MSG_STORAGE_INFORMATION = 261
_MSG_CAMERA_CAPTURE_STATUS = 262
CAMERA_MESSAGES = frozenset(
    {_MSG_CAMERA_INFORMATION, _MSG_CAMERA_SETTINGS, _MSG_STORAGE_INFORMATION,
     _MSG_CAMERA_CAPTURE_STATUS}
)


def _fixed(text: str, size: int) -> list[int]:
    raw = list(text.encode("ascii"))[:size]
    return raw + [0] * (size - len(raw))


class CameraComponent:
    """A nadir still camera: one capture per IMAGE_START_CAPTURE, geotagged.

    A single capture may carry a capture sequence number (param 4, from 1): a command that
    repeats the last sequence number is a retransmission, so it takes no second photo and the
    camera sends that photo's CAMERA_IMAGE_CAPTURED again (its first copy may have been lost)."""

    def __init__(self, link: VehicleLink) -> None:
        self.link = link
        self._last_sequence = 0.0
        self._last_captured: mavlink.MAVLink_message | None = None

    def _send(self, message: mavlink.MAVLink_message) -> None:
        self.link.send(message, component_id=CAMERA_COMPONENT_ID)

    def heartbeat(self) -> mavlink.MAVLink_message:
        return mavlink.MAVLink_heartbeat_message(MAV_TYPE_CAMERA, MAV_AUTOPILOT_INVALID, 0, 0, 4, 3)

    def build(self, msg_id: int) -> mavlink.MAVLink_message | None:
        t_ms = self.link.time_boot_ms()
        if msg_id == _MSG_CAMERA_INFORMATION:
            return mavlink.MAVLink_camera_information_message(
                t_ms, _fixed("mavswarm", 32), _fixed("nadir-still", 32), 1, 4.5, 6.17, 4.55,
                4000, 3000, 0, _CAP_CAPTURE_IMAGE, 0, b"",
            )
        if msg_id == _MSG_CAMERA_SETTINGS:
            return mavlink.MAVLink_camera_settings_message(t_ms, 0, math.nan, math.nan)
        if msg_id == _MSG_STORAGE_INFORMATION:
            return mavlink.MAVLink_storage_information_message(
                t_ms, 1, 1, 2, 65536.0, 0.0, 65536.0, 90.0, 60.0
            )
        if msg_id == _MSG_CAMERA_CAPTURE_STATUS:
            return mavlink.MAVLink_camera_capture_status_message(
                t_ms, 0, 0, 0.0, 0, 65536.0, self.link.ap.photo_count
            )
        return None

    def handle_command(self, a: CommandArgs) -> tuple[int, str | None]:
        from emulator.mavlink.commands import Result

        link = self.link
        if a.command == 2000:  # IMAGE_START_CAPTURE: p2 interval, p3 total images
            total = a.p3 if math.isfinite(a.p3) else 1.0
            if total != 1.0:
                return Result.DENIED, "Camera: only single captures (total images = 1)"
            sequence = a.p4 if math.isfinite(a.p4) and a.p4 >= 1.0 else 0.0
            if sequence and sequence == self._last_sequence:
                captured = self._last_captured
                if captured is not None:
                    link.after_ack(lambda: self._send(captured))
                return Result.ACCEPTED, None
            self._last_sequence = sequence
            link.after_ack(link.ap.take_photo)
            return Result.ACCEPTED, None
        if a.command == 2001:  # IMAGE_STOP_CAPTURE
            return Result.ACCEPTED, None
        if a.command == 530:  # SET_CAMERA_MODE: only image mode (0)
            mode = a.p2 if math.isfinite(a.p2) else 0.0
            return (Result.ACCEPTED, None) if mode == 0.0 else (
                Result.DENIED, "Camera: only image mode is supported"
            )
        legacy = {521: _MSG_CAMERA_INFORMATION, 522: _MSG_CAMERA_SETTINGS,
                  525: _MSG_STORAGE_INFORMATION, 527: _MSG_CAMERA_CAPTURE_STATUS}
        msg_id = legacy[a.command]
        link.after_ack(lambda: self.send_once(msg_id))
        return Result.ACCEPTED, None

    def send_once(self, msg_id: int) -> None:
        message = self.build(msg_id)
        if message is not None:
            self._send(message)

    def image_captured(self, capture: ImageCapture) -> None:
        ap = self.link.ap
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
        self._send(self._last_captured)
