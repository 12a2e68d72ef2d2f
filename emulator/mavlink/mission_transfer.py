"""The mission protocol: upload, download and clear, with retransmission of lost items.

An upload is atomic: the vehicle's mission is replaced only when every item has arrived and
passed validation; a stalled, restarted or refused upload leaves the old mission in place.
Retries and time-outs run on the wall clock (they concern the link, not the flight).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from emulator.flight.mission import (
    MAX_ITEMS,
    MissionItem,
    MissionResult,
    validate_item,
    validate_item_limits,
)
from emulator.flight.refusal import Severity
from emulator.mavlink.codec import mavlink

if TYPE_CHECKING:
    from emulator.mavlink.vehicle_link import VehicleLink

__all__ = ["MissionTransfer"]

MISSION_TYPE_MISSION = 0
MISSION_TYPE_ALL = 255
RETRY_INTERVAL_S = 0.25
MAX_RETRIES = 8


class _Upload:
    __slots__ = ("count", "items", "last_activity_s", "peer", "retries")

    def __init__(self, count: int, peer: tuple[int, int], now_s: float) -> None:
        self.count = count
        self.items: list[MissionItem] = []
        self.peer = peer
        self.last_activity_s = now_s
        self.retries = 0


class MissionTransfer:
    """Mission micro-service state of one vehicle."""

    def __init__(self, link: VehicleLink) -> None:
        self.link = link
        self._upload: _Upload | None = None
        # (peer, last seq, result) of the upload that ended last: its last item sent again
        # means the ACK was lost, and gets the same ACK again (as PX4 does)
        self._ended: tuple[tuple[int, int], int, int] | None = None

    @property
    def uploading(self) -> bool:
        return self._upload is not None

    def _ack(self, peer: tuple[int, int], result: int, mission_type: int = 0) -> None:
        self.link.send(mavlink.MAVLink_mission_ack_message(peer[0], peer[1], result, mission_type))

    def _request(self, seq: int) -> None:
        up = self._upload
        assert up is not None
        self.link.send(mavlink.MAVLink_mission_request_int_message(up.peer[0], up.peer[1], seq, 0))

    # ------------------------------------------------------------------ upload
    def on_count(self, m, peer: tuple[int, int], now_s: float) -> None:
        mission_type = getattr(m, "mission_type", 0)
        if mission_type != MISSION_TYPE_MISSION:
            result = MissionResult.ACCEPTED if m.count == 0 else MissionResult.UNSUPPORTED
            self._ack(peer, result, mission_type)
            return
        if m.count > MAX_ITEMS:
            self._ack(peer, MissionResult.NO_SPACE)
            self.link.statustext(Severity.WARNING,
                                 f"Mission refused: {m.count} items > {MAX_ITEMS}")
            return
        if self._upload is not None:
            self.link.statustext(Severity.INFO, "Mission upload restarted")
        self._ended = None
        if m.count == 0:
            self._upload = None
            self.link.ap.mission.clear()
            self._ack(peer, MissionResult.ACCEPTED)
            return
        self._upload = _Upload(m.count, peer, now_s)
        self._request(0)

    def on_item(self, m, peer: tuple[int, int], now_s: float, *, is_int: bool) -> None:
        up = self._upload
        if getattr(m, "mission_type", 0) != MISSION_TYPE_MISSION:
            return
        if up is None:
            ended = self._ended
            if ended is not None and ended[:2] == (peer, m.seq):
                self._ack(peer, ended[2])  # a repeat of the last item: the ACK was lost
                return
            self._ack(peer, MissionResult.DENIED)
            return
        if peer != up.peer:  # PX4: "partner id mismatch", the item is ignored
            self.link.statustext(Severity.WARNING, "Mission item from another GCS ignored")
            return
        expected = len(up.items)
        up.last_activity_s = now_s
        if m.seq != expected:
            up.retries += 1
            self._request(expected)
            return
        item = _to_item(m, is_int)
        ap = self.link.ap
        code, reason = validate_item(
            item, ap.fleet.world.origin, ap.home_m, ap.params["GF_MAX_VER_DIST"],
            ap.params["GF_MAX_HOR_DIST"],
        )
        if code == MissionResult.ACCEPTED:
            code, reason = validate_item_limits(item, ap.params)
        if code != MissionResult.ACCEPTED:
            self._upload = None
            self._ended = (peer, m.seq, code)
            self._ack(peer, code)
            self.link.statustext(Severity.WARNING, reason)
            return
        up.items.append(item)
        up.retries = 0
        if len(up.items) < up.count:
            self._request(len(up.items))
            return
        self._upload = None
        self._ended = (peer, m.seq, MissionResult.ACCEPTED)
        ap.mission.replace(up.items)
        self._ack(peer, MissionResult.ACCEPTED)

    def tick(self, now_s: float) -> None:
        """Re-request a lost item; give up after MAX_RETRIES silent intervals."""
        up = self._upload
        if up is None or now_s - up.last_activity_s < RETRY_INTERVAL_S:
            return
        if up.retries >= MAX_RETRIES:
            self._upload = None
            self._ack(up.peer, MissionResult.OPERATION_CANCELLED)
            self.link.statustext(Severity.WARNING, "Mission upload timed out: kept old mission")
            return
        up.retries += 1
        up.last_activity_s = now_s
        self._request(len(up.items))

    # ---------------------------------------------------------------- download
    def on_request_list(self, m, peer: tuple[int, int]) -> None:
        mission_type = getattr(m, "mission_type", 0)
        count = self.link.ap.mission.total if mission_type == MISSION_TYPE_MISSION else 0
        self.link.send(mavlink.MAVLink_mission_count_message(peer[0], peer[1], count, mission_type))

    def on_request(self, m, peer: tuple[int, int], *, wants_int: bool) -> None:
        mission_type = getattr(m, "mission_type", 0)
        items = self.link.ap.mission.items if mission_type == MISSION_TYPE_MISSION else ()
        if not 0 <= m.seq < len(items):
            self._ack(peer, MissionResult.INVALID_SEQUENCE, mission_type)
            return
        it = items[m.seq]
        current = int(it.seq == self.link.ap.mission.current)
        if wants_int:
            msg = mavlink.MAVLink_mission_item_int_message(
                peer[0], peer[1], it.seq, it.frame, it.command, current, it.autocontinue,
                it.param1, it.param2, it.param3, it.param4, it.x, it.y, it.z, 0,
            )
        else:
            msg = mavlink.MAVLink_mission_item_message(
                peer[0], peer[1], it.seq, it.frame, it.command, current, it.autocontinue,
                it.param1, it.param2, it.param3, it.param4, it.x * 1e-7, it.y * 1e-7, it.z, 0,
            )
        self.link.send(msg)

    # ------------------------------------------------------------------ others
    def on_clear_all(self, m, peer: tuple[int, int]) -> None:
        mission_type = getattr(m, "mission_type", 0)
        if mission_type in (MISSION_TYPE_MISSION, MISSION_TYPE_ALL):
            self._upload = None
            self.link.ap.mission.clear()
        self._ack(peer, MissionResult.ACCEPTED, mission_type)

    def on_set_current(self, m) -> None:
        from emulator.flight.refusal import CommandRefused

        try:
            self.link.ap.mission.set_current(m.seq)
        except CommandRefused as refusal:
            self.link.statustext(Severity.WARNING, str(refusal))
            self.link.send_once(42)


def _to_item(m, is_int: bool) -> MissionItem:
    if is_int:
        x, y = int(m.x), int(m.y)
    else:
        x = round(m.x * 1e7) if math.isfinite(m.x) else 2**31 - 1
        y = round(m.y * 1e7) if math.isfinite(m.y) else 2**31 - 1
    return MissionItem(
        seq=m.seq, frame=m.frame, command=m.command, param1=m.param1, param2=m.param2,
        param3=m.param3, param4=m.param4, x=x, y=y, z=m.z, autocontinue=m.autocontinue,
    )
