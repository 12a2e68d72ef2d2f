"""A mission's payload items, reached in flight: the gimbal and the camera act on them.

DO_GIMBAL_MANAGER_PITCHYAW / _CONFIGURE items aim the gimbal of a vehicle that has one, as
the vehicle itself (a ground station in control of the gimbal keeps it: the item is then
refused with its reason); the camera items (SET_CAMERA_MODE, VIDEO_START_CAPTURE,
VIDEO_STOP_CAPTURE) go to the camera component. Other payload items change nothing.
"""

from __future__ import annotations

from emulator.flight.mission import MissionItem
from emulator.mavlink.camera_video import VIDEO_COMMANDS
from emulator.mavlink.command_args import CommandArgs
from emulator.mavlink.gimbal import GIMBAL_COMMANDS
from emulator.mavlink.reply import Reply
from emulator.mavlink.vehicle import Vehicle
from mavlink_vocabulary import MavComponent

__all__ = ["payload_item_reply"]


def payload_item_reply(v: Vehicle, item: MissionItem) -> Reply | None:
    """What the payload answers to a reached mission item (None: nothing acts on it)."""
    args = CommandArgs(item.command, item.param1, item.param2, item.param3, item.param4,
                       None, None, item.z, item.frame, float(item.x))
    if item.command in GIMBAL_COMMANDS and v.gimbal is not None:
        return v.gimbal.handle_command(v.ap, args, (v.ap.system_id, MavComponent.AUTOPILOT1))
    if item.command in VIDEO_COMMANDS:
        return v.camera.handle_command(v.ap, args, v.wall_now_s)
    return None
