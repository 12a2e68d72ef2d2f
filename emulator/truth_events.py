"""The kinds of ground-truth event the emulator records (`TruthEvent.kind`), one word each.

Values are the words stored in truth files and replays; the checks, the replay and the console
read them by these members.
"""

from __future__ import annotations

from enum import StrEnum

__all__ = ["TruthEventKind"]


class TruthEventKind(StrEnum):
    # arming, flight and landing
    ARM = "arm"
    DISARM = "disarm"
    KILL = "kill"
    MODE = "mode"
    TAKEOFF = "takeoff"
    TAKEOFF_COMPLETE = "takeoff_complete"
    LANDED = "landed"
    HOME = "home"
    ORBIT = "orbit"
    OBSTACLE_STOP = "obstacle_stop"
    # missions
    MISSION_START = "mission_start"
    MISSION_ITEM_REACHED = "mission_item_reached"
    MISSION_COMPLETE = "mission_complete"
    # payload and sensors
    PHOTO = "photo"
    VIDEO_START = "video_start"
    VIDEO_STOP = "video_stop"
    GIMBAL = "gimbal"
    CALIBRATION = "calibration"
    FOLLOW_TARGET = "follow_target"
    FOLLOW_TARGET_LOST = "follow_target_lost"
    # battery
    CHARGING = "charging"
    CHARGED = "charged"
    # failsafes and failures
    FAILSAFE = "failsafe"
    FAILURE = "failure"
    FAILURE_CLEARED = "failure_cleared"
    # the MAVLink link
    LINK_FAULTS = "link_faults"
    LINK_OUTAGE = "link_outage"
    LINK_RESTORED = "link_restored"
    LINK_LOST = "link_lost"
    LINK_REGAINED = "link_regained"
    # the radio between drones
    MESSAGE_SENT = "message_sent"
    MESSAGE_BROADCAST = "message_broadcast"
    MESSAGE_DROPPED = "message_dropped"
    MESSAGES_READ = "messages_read"
    # the swarm and its operator
    JOINED = "joined"
    LEFT = "left"
    OPERATOR_REPAIR = "operator_repair"
    OPERATOR_PLACE = "operator_place"
    OPERATOR_BATTERY = "operator_battery"
