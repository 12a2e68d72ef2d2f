"""The MAVLink protocol of one network, sans I/O: datagrams in, datagrams out, timers.

One `NetworkProtocol` serves the vehicles behind one socket (all of them in the default
shared topology, one each in per-vehicle mode), in the style of aioquic: the owner feeds
it what arrived with `receive_datagram(data, addr, now)`, sends what `datagrams_to_send(now)`
returns, and calls `handle_timer(now)` once `next_timer()` has passed. It reads no clock and
touches no socket; `now` is the wall clock of whoever drives it (emulator.transport over
UDP, or a test in memory).

Incoming frames are decoded here and routed by `target_system` (a broadcast reaches every
vehicle). Outgoing frames go to the fixed destinations and to every peer that has talked to
the network in the last `PEER_TIMEOUT_S` (so `udpout://` clients work). Replies go out one
frame per datagram; periodic telemetry, sent between `begin_batch()` and `end_batch()`, is
packed several frames to a datagram (MAVLink is a byte stream: receivers parse every frame of
a datagram), which saves most of the system calls of a large swarm.

With link faults (emulator.link_faults), each frame, in either direction, first asks the link
gate its fate: dropped, delivered now, or delivered after a delay (wall seconds), maybe twice.
A delayed downlink frame's delay runs from the next `datagrams_to_send`, which its owner calls
right after the frame was queued.
"""

from __future__ import annotations

import bisect
import heapq
import itertools
import logging
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field

from emulator.link_faults import DOWNLINK, UPLINK, LinkGate
from emulator.mavlink.codec import DatagramDecoder, mavlink
from emulator.mavlink.vehicle_link import VehicleLink
from mavlink_vocabulary import MessageId

__all__ = ["MAX_BATCH_BYTES", "PEER_TIMEOUT_S", "Address", "LinkStats", "NetworkProtocol",
           "frame_msg_id"]

PEER_TIMEOUT_S = 10.0
MAX_BATCH_BYTES = 1200  # stays below any loopback or Ethernet MTU
Address = tuple[str, int]
# broadcasts of these are for a ground station, never for a vehicle
_NOT_FOR_VEHICLES = frozenset({MessageId.PING, MessageId.REQUEST_DATA_STREAM})
# messages whose target system is not in a field named target_system
_TARGET_FIELDS = {MessageId.MANUAL_CONTROL: "target"}
# messages with no target system that every vehicle behind the socket hears
_FOR_EVERY_VEHICLE = frozenset({MessageId.FOLLOW_TARGET})
log = logging.getLogger("mavswarm.protocol")


@dataclass(slots=True)
class LinkStats:
    datagrams_in: int = 0
    datagrams_out: int = 0
    frames_out: int = 0
    unroutable: int = 0
    send_errors: int = 0  # counted by the transport
    handler_errors: int = 0
    peers: set[Address] = field(default_factory=set)


class NetworkProtocol:
    """The vehicles behind one socket and the ground stations they talk to."""

    def __init__(self, destinations: Iterable[Address], gate: LinkGate | None = None) -> None:
        self.links: dict[int, VehicleLink] = {}
        self._fixed = tuple(dict.fromkeys(destinations))
        self._peers: dict[Address, float] = {}
        self._targets: tuple[Address, ...] = self._fixed
        self.decoder = DatagramDecoder()
        self.stats = LinkStats()
        self.gate = gate  # link faults (emulator.link_faults), if any
        self.is_open = False  # frames are queued only while a transport serves the network
        self.on_pending: Callable[[], None] | None = None  # told when the queue fills
        # a ground station began talking (told the wall-clock time)
        self.on_new_peer: Callable[[float], None] | None = None
        self._queue: list[bytes] = []
        self._batch = bytearray()
        self._batching = False
        self._late_down: list[tuple[float, bytes]] = []  # (delay_s, frame): not yet timed
        self._timers: list[tuple[float, int, VehicleLink | None, object]] = []
        self._order = itertools.count()

    def add(self, link: VehicleLink) -> None:
        self.links[link.system_id] = link

    def open(self) -> None:
        self.is_open = True

    def close(self) -> None:
        self.is_open = False
        self._queue.clear()
        self._batch.clear()
        self._late_down.clear()
        self._timers.clear()

    # ---------------------------------------------------------------- receive
    def receive_datagram(self, data: bytes, addr: Address, now: float) -> None:
        """Decode one datagram from `addr` and hand its messages to their vehicles."""
        self.stats.datagrams_in += 1
        addr = addr[:2]
        known = addr in self._peers
        self._peers[addr] = now
        if not known:
            self._refresh_targets()
            if self.on_new_peer is not None:
                self.on_new_peer(now)
        links = self.links
        for m in self.decoder.decode(data):
            msg_id = m.get_msgId()
            target = getattr(m, _TARGET_FIELDS.get(msg_id, "target_system"), None)
            if target is None:
                if msg_id not in _FOR_EVERY_VEHICLE:
                    continue
                target = 0
            if target == 0:
                if msg_id in _NOT_FOR_VEHICLES:
                    continue
                for link in links.values():
                    self._deliver(link, m, now)
            else:
                addressed = links.get(target)
                if addressed is None:
                    self.stats.unroutable += 1
                else:
                    self._deliver(addressed, m, now)

    def _deliver(self, link: VehicleLink, m: mavlink.MAVLink_message, now: float) -> None:
        gate = self.gate
        if gate is not None and gate.active:
            fate = gate.fate(link.k, UPLINK, m.get_msgId())
            if fate is not None:
                for delay_s in fate:
                    if delay_s > 0.0:
                        heapq.heappush(self._timers, (now + delay_s, next(self._order), link, m))
                    else:
                        self._handle(link, m, now)
                return
        self._handle(link, m, now)

    def _handle(self, link: VehicleLink, m: mavlink.MAVLink_message, now: float) -> None:
        # A handler bug is logged with its traceback and counted, and the network keeps
        # serving every other vehicle.
        try:
            link.handle(m, now)
        except Exception:
            self.stats.handler_errors += 1
            log.exception("vehicle %d failed to handle %s", link.system_id, m.get_type())

    # ------------------------------------------------------------------ timers
    def next_timer(self) -> float | None:
        """When `handle_timer` has something to do next (wall seconds), None if never."""
        return self._timers[0][0] if self._timers else None

    def handle_timer(self, now: float) -> bool:
        """Deliver what is due by `now`: delayed frames in both directions. True when a
        message reached a vehicle."""
        self._time_late_frames(now)
        timers, delivered = self._timers, False
        while timers and timers[0][0] <= now:
            _due, _order, link, item = heapq.heappop(timers)
            if link is None:
                assert isinstance(item, bytes)
                self._queue.append(item)
            else:
                assert isinstance(item, mavlink.MAVLink_message)
                self._handle(link, item, now)
                delivered = True
        return delivered

    def _time_late_frames(self, now: float) -> None:
        for delay_s, frame in self._late_down:
            heapq.heappush(self._timers, (now + delay_s, next(self._order), None, frame))
        self._late_down.clear()

    # ------------------------------------------------------------------- send
    def send_frame(self, k: int, frame: bytes) -> None:
        """Queue one encoded frame of vehicle k (index k in the fleet)."""
        if not self.is_open:
            return
        self.stats.frames_out += 1
        gate = self.gate
        if gate is not None and gate.active:
            fate = gate.fate(k, DOWNLINK, frame_msg_id(frame))
            if fate is not None:
                for delay_s in fate:
                    if delay_s > 0.0:
                        self._late_down.append((delay_s, frame))
                        self._notify()
                    else:
                        self._queue_now(frame)
                return
        self._queue_now(frame)

    def send_frames(self, data: bytes, ends: Sequence[int]) -> bool:
        """Queue the frames data[ends[i-1]:ends[i]] (data[:ends[0]] first) packed into the
        datagrams `send_frame` would pack them into one by one, without a call per frame.
        False, queuing nothing, unless frames are being batched on a clean link (the caller
        then sends each with `send_frame`)."""
        if not self.can_send_frames():
            return False
        self.stats.frames_out += len(ends)
        batch, start, i, count = self._batch, 0, 0, len(ends)
        while i < count:
            # The frames from i on that still fit into the datagram being packed.
            j = bisect.bisect_right(ends, start + MAX_BATCH_BYTES - len(batch), i)
            if j == i:
                self._end_datagram()
                j = max(bisect.bisect_right(ends, start + MAX_BATCH_BYTES, i), i + 1)
            batch += data[start:ends[j - 1]]
            start, i = ends[j - 1], j
            if i < count:
                self._end_datagram()
        return True

    def can_send_frames(self) -> bool:
        """Whether `send_frames` takes a batch now (batching, open, a clean link)."""
        gate = self.gate
        return self._batching and self.is_open and (gate is None or not gate.active)

    def _queue_now(self, frame: bytes) -> None:
        if self._batching:
            if len(self._batch) + len(frame) > MAX_BATCH_BYTES:
                self._end_datagram()
            self._batch += frame
            return
        self._queue.append(frame)
        self._notify()

    def _end_datagram(self) -> None:
        if self._batch:
            self._queue.append(bytes(self._batch))
            self._batch.clear()
            self._notify()

    def begin_batch(self) -> None:
        """Pack the frames sent from now to `end_batch` several to a datagram."""
        self._batching = True

    def end_batch(self) -> None:
        self._batching = False
        self._end_datagram()

    def _notify(self) -> None:
        if self.on_pending is not None:
            self.on_pending()

    def datagrams_to_send(self, now: float) -> list[tuple[bytes, Address]]:
        """(datagram, destination) pairs to send now; each datagram goes to every target."""
        self.handle_timer(now)
        queue, self._queue = self._queue, []
        self.stats.datagrams_out += len(queue)
        targets = self._targets
        return [(data, addr) for data in queue for addr in targets]

    # ------------------------------------------------------------------- peers
    def expire_peers(self, now: float) -> None:
        stale = [a for a, t in self._peers.items() if now - t > PEER_TIMEOUT_S]
        for addr in stale:
            del self._peers[addr]
        if stale:
            self._refresh_targets()

    def _refresh_targets(self) -> None:
        self._targets = tuple(dict.fromkeys(self._fixed + tuple(self._peers)))
        self.stats.peers = set(self._peers)


def frame_msg_id(frame: bytes) -> int:
    """The message id of one encoded MAVLink frame (v2: 24 bits at offset 7; v1: offset 5)."""
    if frame[:1] == b"\xfd" and len(frame) >= 10:
        return int.from_bytes(frame[7:10], "little")
    return frame[5] if len(frame) > 5 else -1
