"""Which messages a client sends only to ask: answered, with the vehicle's state left as it
was (emulator.telemetry_bursts sends a vehicle's telemetry again only when it may differ)."""

from __future__ import annotations

from emulator.mavlink.codec import mavlink
from mavlink_vocabulary import MavCmd, MessageId

__all__ = ["QUERY_COMMANDS", "QUERY_MESSAGES", "changes_state"]

# What a client sends that only asks: answered, but the vehicle's state stays as it was.
QUERY_MESSAGES = frozenset({
    MessageId.HEARTBEAT, MessageId.PING, MessageId.TIMESYNC, MessageId.PARAM_REQUEST_READ,
    MessageId.PARAM_REQUEST_LIST, MessageId.MISSION_REQUEST_LIST, MessageId.MISSION_REQUEST,
    MessageId.MISSION_REQUEST_INT,
})
QUERY_COMMANDS = frozenset({
    MavCmd.REQUEST_MESSAGE, MavCmd.REQUEST_AUTOPILOT_CAPABILITIES, MavCmd.GET_HOME_POSITION,
    MavCmd.SET_MESSAGE_INTERVAL, MavCmd.REQUEST_CAMERA_INFORMATION,
    MavCmd.REQUEST_CAMERA_SETTINGS, MavCmd.REQUEST_STORAGE_INFORMATION,
    MavCmd.REQUEST_CAMERA_CAPTURE_STATUS, MavCmd.REQUEST_VIDEO_STREAM_INFORMATION,
    MavCmd.REQUEST_VIDEO_STREAM_STATUS,
})
_COMMANDS = (MessageId.COMMAND_LONG, MessageId.COMMAND_INT)


def changes_state(m: mavlink.MAVLink_message) -> bool:
    """Whether handling `m` may change what its vehicle's telemetry shows (False only for
    the queries above)."""
    msg_id = m.get_msgId()
    if msg_id in _COMMANDS:
        return getattr(m, "command", None) not in QUERY_COMMANDS
    return msg_id not in QUERY_MESSAGES
