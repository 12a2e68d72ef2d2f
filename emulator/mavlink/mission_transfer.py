"""The mission protocol: upload, download and clear, with retransmission of lost items.

It carries the three plan types, as PX4: the mission, the fence and the rally points
(mission_type MISSION, FENCE, RALLY; MISSION_CLEAR_ALL of type ALL clears all three).
An upload is atomic: the vehicle's plan is replaced only when every item has arrived and
passed validation; a stalled, restarted or refused upload leaves the old plan in place.
Retries and time-outs run on the wall clock (they concern the link, not the flight). Every
method returns the messages to send in answer; nothing here sends.
"""

from __future__ import annotations

import math

from emulator.flight.autopilot import Autopilot
from emulator.flight.mission import (
    MAX_ITEMS,
    MissionItem,
    MissionResult,
    validate_item,
    validate_item_limits,
)
from emulator.flight.refusal import CommandRefused, Severity
from emulator.mavlink import messages as msgs
from emulator.mavlink.codec import mavlink
from mavlink_vocabulary import MavMissionResult, MavMissionType

__all__ = ["MAX_RETRIES", "RETRY_INTERVAL_S", "MissionTransfer", "wire_result"]

RETRY_INTERVAL_S = 0.25
MAX_RETRIES = 8
INT32_LIMIT = 2**31
NO_COORDINATE = INT32_LIMIT - 1  # an unset MISSION_ITEM_INT x / y
Peer = tuple[int, int]
_PLAN_TYPES = (MavMissionType.MISSION, MavMissionType.FENCE, MavMissionType.RALLY)
Messages = list[mavlink.MAVLink_message]
def wire_result(code: int) -> MavMissionResult:
    """The MAV_MISSION_RESULT of a result code of emulator.flight.mission (ERROR if unknown)."""
    try:
        return MavMissionResult(code)
    except ValueError:
        return MavMissionResult.ERROR


class _Upload:
    __slots__ = ("count", "items", "last_activity_s", "mission_type", "peer", "retries")

    def __init__(self, count: int, peer: Peer, now_s: float, mission_type: int) -> None:
        self.count = count
        self.mission_type = mission_type
        self.items: list[MissionItem] = []
        self.peer = peer
        self.last_activity_s = now_s
        self.retries = 0


def _ack(peer: Peer, result: MavMissionResult,
         mission_type: int = MavMissionType.MISSION) -> mavlink.MAVLink_message:
    return mavlink.MAVLink_mission_ack_message(peer[0], peer[1], result, mission_type)


class MissionTransfer:
    """Mission micro-service state of one vehicle."""

    def __init__(self, ap: Autopilot) -> None:
        self.ap = ap
        self._upload: _Upload | None = None
        # (peer, last seq, result) of the upload that ended last: its last item sent again
        # means the ACK was lost, and gets the same ACK again (as PX4 does)
        self._ended: tuple[Peer, int, MavMissionResult] | None = None

    @property
    def uploading(self) -> bool:
        return self._upload is not None

    def _request(self, seq: int) -> mavlink.MAVLink_message:
        up = self._upload
        assert up is not None
        return mavlink.MAVLink_mission_request_int_message(
            up.peer[0], up.peer[1], seq, up.mission_type)

    # ------------------------------------------------------------------ upload
    def on_count(self, m, peer: Peer, now_s: float) -> Messages:
        mission_type = getattr(m, "mission_type", MavMissionType.MISSION)
        if mission_type not in _PLAN_TYPES:
            return [_ack(peer, MavMissionResult.UNSUPPORTED, mission_type)]
        if m.count > MAX_ITEMS:
            return [_ack(peer, MavMissionResult.NO_SPACE, mission_type),
                    msgs.statustext(Severity.WARNING,
                                    f"Mission refused: {m.count} items > {MAX_ITEMS}")]
        out: Messages = []
        if self._upload is not None:
            out.append(msgs.statustext(Severity.INFO, "Mission upload restarted"))
        self._ended = None
        if m.count == 0:
            self._upload = None
            self._clear(mission_type)
            out.append(_ack(peer, MavMissionResult.ACCEPTED, mission_type))
            return out
        self._upload = _Upload(m.count, peer, now_s, mission_type)
        out.append(self._request(0))
        return out

    def on_item(self, m, peer: Peer, now_s: float, *, is_int: bool) -> Messages:
        up = self._upload
        mission_type = getattr(m, "mission_type", MavMissionType.MISSION)
        if up is None:
            ended = self._ended
            if ended is not None and ended[:2] == (peer, m.seq):
                # a repeat of the last item: the ACK was lost
                return [_ack(peer, ended[2], mission_type)]
            return [_ack(peer, MavMissionResult.DENIED, mission_type)]
        if mission_type != up.mission_type:
            return []
        if peer != up.peer:  # PX4: "partner id mismatch", the item is ignored
            return [msgs.statustext(Severity.WARNING, "Mission item from another GCS ignored")]
        expected = len(up.items)
        up.last_activity_s = now_s
        if m.seq != expected:
            up.retries += 1
            return [self._request(expected)]
        item = _to_item(m, is_int)
        ap = self.ap
        if mission_type == MavMissionType.MISSION:
            code, reason = validate_item(
                item, ap.fleet.world.origin, ap.home_m, ap.params["GF_MAX_VER_DIST"],
                ap.params["GF_MAX_HOR_DIST"],
            )
            if code == MissionResult.ACCEPTED:
                code, reason = validate_item_limits(item, ap.params)
        else:  # fence and rally items are checked as a whole plan once all have arrived
            code, reason = MissionResult.ACCEPTED, ""
        up.items.append(item)
        up.retries = 0
        if code == MissionResult.ACCEPTED and len(up.items) < up.count:
            return [self._request(len(up.items))]
        self._upload = None
        if code == MissionResult.ACCEPTED:
            code, reason = self._store(mission_type, up.items)
        result = wire_result(code)
        self._ended = (peer, m.seq, result)
        if result != MavMissionResult.ACCEPTED:
            return [_ack(peer, result, mission_type), msgs.statustext(Severity.WARNING, reason)]
        return [_ack(peer, MavMissionResult.ACCEPTED, mission_type)]

    def _store(self, mission_type: int, items: list[MissionItem]) -> tuple[int, str]:
        """Replace the plan of `mission_type`: (MAV_MISSION_RESULT, reason)."""
        ap = self.ap
        try:
            if mission_type == MavMissionType.FENCE:
                ap.geofence.set_fence(items)
            elif mission_type == MavMissionType.RALLY:
                ap.geofence.set_rally(items)
            else:
                ap.geofence.check_mission(items)
                ap.mission.replace(items)
        except CommandRefused as refusal:
            return MissionResult.INVALID, str(refusal)
        return MissionResult.ACCEPTED, ""

    def _clear(self, mission_type: int) -> None:
        ap = self.ap
        if mission_type in (MavMissionType.MISSION, MavMissionType.ALL):
            ap.mission.clear()
        if mission_type in (MavMissionType.FENCE, MavMissionType.ALL):
            ap.geofence.set_fence([])
        if mission_type in (MavMissionType.RALLY, MavMissionType.ALL):
            ap.geofence.set_rally([])

    def _items(self, mission_type: int) -> tuple[MissionItem, ...] | list[MissionItem]:
        if mission_type == MavMissionType.FENCE:
            return self.ap.geofence.fence_items
        if mission_type == MavMissionType.RALLY:
            return self.ap.geofence.rally_items
        if mission_type == MavMissionType.MISSION:
            return self.ap.mission.items
        return ()

    def tick(self, now_s: float) -> Messages:
        """Re-request a lost item; give up after MAX_RETRIES silent intervals."""
        up = self._upload
        if up is None or now_s - up.last_activity_s < RETRY_INTERVAL_S:
            return []
        if up.retries >= MAX_RETRIES:
            self._upload = None
            return [_ack(up.peer, MavMissionResult.OPERATION_CANCELLED),
                    msgs.statustext(Severity.WARNING, "Mission upload timed out: kept old mission")]
        up.retries += 1
        up.last_activity_s = now_s
        return [self._request(len(up.items))]

    # ---------------------------------------------------------------- download
    def on_request_list(self, m, peer: Peer) -> Messages:
        mission_type = getattr(m, "mission_type", MavMissionType.MISSION)
        count = len(self._items(mission_type))
        return [mavlink.MAVLink_mission_count_message(peer[0], peer[1], count, mission_type)]

    def on_request(self, m, peer: Peer, *, wants_int: bool) -> Messages:
        mission_type = getattr(m, "mission_type", MavMissionType.MISSION)
        items = self._items(mission_type)
        if not 0 <= m.seq < len(items):
            return [_ack(peer, MavMissionResult.INVALID_SEQUENCE, mission_type)]
        it = items[m.seq]
        current = int(mission_type == MavMissionType.MISSION and it.seq == self.ap.mission.current)
        if wants_int:
            return [mavlink.MAVLink_mission_item_int_message(
                peer[0], peer[1], it.seq, it.frame, it.command, current, it.autocontinue,
                it.param1, it.param2, it.param3, it.param4, it.x, it.y, it.z, mission_type,
            )]
        return [mavlink.MAVLink_mission_item_message(
            peer[0], peer[1], it.seq, it.frame, it.command, current, it.autocontinue,
            it.param1, it.param2, it.param3, it.param4, it.x * 1e-7, it.y * 1e-7, it.z,
            mission_type,
        )]

    # ------------------------------------------------------------------ others
    def on_clear_all(self, m, peer: Peer) -> Messages:
        mission_type = getattr(m, "mission_type", MavMissionType.MISSION)
        if mission_type not in (*_PLAN_TYPES, MavMissionType.ALL):
            return [_ack(peer, MavMissionResult.UNSUPPORTED, mission_type)]
        up = self._upload
        if up is not None and mission_type in (up.mission_type, MavMissionType.ALL):
            self._upload = None
        self._clear(mission_type)
        return [_ack(peer, MavMissionResult.ACCEPTED, mission_type)]

    def on_set_current(self, m) -> Messages:
        try:
            self.ap.mission.set_current(m.seq)
        except CommandRefused as refusal:
            return [msgs.statustext(Severity.WARNING, str(refusal)), msgs.mission_current(self.ap)]
        return []


def _int32(value: int) -> int:
    return min(max(value, -INT32_LIMIT), INT32_LIMIT - 1)


def _to_item(m, is_int: bool) -> MissionItem:
    if is_int:
        x, y = int(m.x), int(m.y)
    else:  # degrees as MISSION_ITEM_INT's int32 (clamped: a download must stay encodable)
        x = _int32(round(m.x * 1e7)) if math.isfinite(m.x) else NO_COORDINATE
        y = _int32(round(m.y * 1e7)) if math.isfinite(m.y) else NO_COORDINATE
    return MissionItem(
        seq=m.seq, frame=m.frame, command=m.command, param1=m.param1, param2=m.param2,
        param3=m.param3, param4=m.param4, x=x, y=y, z=m.z, autocontinue=m.autocontinue,
    )
