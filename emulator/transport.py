"""UDP transport: moves MAVLink datagrams between sockets and vehicle links, nothing else.

One `UdpEndpoint` owns one non-blocking socket and the vehicles behind it (all of them in
the default shared topology, one each in per-vehicle mode). Incoming frames are routed by
`target_system`; outgoing frames go to the configured ground-station ports and to every peer
that has talked to the socket in the last `PEER_TIMEOUT_S` (so `udpout://` clients work).

Every readable datagram is drained at once when the socket becomes readable. Replies go out
immediately, one frame per datagram; periodic telemetry is packed several frames to a
datagram (MAVLink is a byte stream: receivers parse every frame in a datagram), which saves
most of the system calls of a large swarm.

With link faults (emulator.link_faults), each frame, in either direction, first asks the link
gate its fate: dropped, delivered now, or delivered after a delay (loop.call_later), maybe
twice.
"""

from __future__ import annotations

import asyncio
import bisect
import logging
import socket
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field

from emulator.link_faults import DOWNLINK, UPLINK, LinkGate
from emulator.mavlink.codec import DatagramDecoder
from emulator.mavlink.vehicle_link import VehicleLink

__all__ = ["MAX_BATCH_BYTES", "PEER_TIMEOUT_S", "LinkStats", "UdpEndpoint"]

PEER_TIMEOUT_S = 10.0
MAX_BATCH_BYTES = 1200  # stays below any loopback or Ethernet MTU
RECV_BYTES = 65535
Address = tuple[str, int]
log = logging.getLogger("mavswarm.transport")


@dataclass(slots=True)
class LinkStats:
    datagrams_in: int = 0
    datagrams_out: int = 0
    frames_out: int = 0
    unroutable: int = 0
    send_errors: int = 0
    handler_errors: int = 0
    peers: set[Address] = field(default_factory=set)


class UdpEndpoint:
    """One UDP socket serving the vehicles in `links`."""

    def __init__(self, links: Iterable[VehicleLink], destinations: Iterable[Address],
                 wall_clock: Callable[[], float], on_receive: Callable[[], None]) -> None:
        self.links = {link.system_id: link for link in links}
        self._fixed = tuple(dict.fromkeys(destinations))
        self._peers: dict[Address, float] = {}
        self._targets: tuple[Address, ...] = self._fixed
        self._wall_clock = wall_clock
        self._on_receive = on_receive
        self.decoder = DatagramDecoder()
        self.stats = LinkStats()
        self._sock: socket.socket | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._batch = bytearray()
        self.batching = False
        self.gate: LinkGate | None = None  # link faults (emulator.link_faults), if any

    def open(self, host: str, port: int) -> None:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 21)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 1 << 21)
            sock.bind((host, port))
        except OSError:
            sock.close()
            raise
        sock.setblocking(False)
        self._sock = sock
        self._loop = asyncio.get_running_loop()
        self._loop.add_reader(sock.fileno(), self._drain)

    @property
    def is_open(self) -> bool:
        return self._sock is not None

    @property
    def local_address(self) -> Address:
        assert self._sock is not None
        return self._sock.getsockname()[:2]

    def close(self) -> None:
        if self._sock is not None:
            if self._loop is not None and not self._loop.is_closed():
                self._loop.remove_reader(self._sock.fileno())
            self._sock.close()
            self._sock = None

    # ---------------------------------------------------------------- receive
    def _drain(self) -> None:
        sock = self._sock
        received = False
        while sock is not None:
            try:
                data, addr = sock.recvfrom(RECV_BYTES)
            except (BlockingIOError, InterruptedError):
                break
            except OSError:  # ICMP port unreachable from a ground-station port nobody opened
                self.stats.send_errors += 1
                continue
            received = True
            self.datagram_received(data, addr)
            sock = self._sock
        if received:
            self._on_receive()

    def datagram_received(self, data: bytes, addr: Address) -> None:
        now = self._wall_clock()
        self.stats.datagrams_in += 1
        addr = addr[:2]
        if addr not in self._peers:
            self._peers[addr] = now
            self._refresh_targets()
        else:
            self._peers[addr] = now
        links = self.links
        for m in self.decoder.decode(data):
            target = getattr(m, "target_system", None)
            if target is None:
                continue
            if target == 0:
                if m.get_type() in ("PING", "REQUEST_DATA_STREAM"):
                    continue
                for link in links.values():
                    self._deliver(link, m, now)
            else:
                addressed = links.get(target)
                if addressed is None:
                    self.stats.unroutable += 1
                else:
                    self._deliver(addressed, m, now)

    def _deliver(self, link: VehicleLink, m, now: float) -> None:
        gate = self.gate
        if gate is not None and gate.active:
            fate = gate.fate(link.k, UPLINK, m.get_msgId())
            if fate is not None:
                for delay_s in fate:
                    if delay_s > 0.0 and self._loop is not None:
                        self._loop.call_later(delay_s, self._deliver_late, link, m)
                    else:
                        self._handle(link, m, now)
                return
        self._handle(link, m, now)

    def _deliver_late(self, link: VehicleLink, m) -> None:
        if self._sock is not None:
            self._handle(link, m, self._wall_clock())
            self._on_receive()

    def _handle(self, link: VehicleLink, m, now: float) -> None:
        # The I/O edge: a handler bug is logged with its traceback and counted, and the
        # socket keeps serving every other vehicle.
        try:
            link.handle(m, now)
        except Exception:
            self.stats.handler_errors += 1
            log.exception("vehicle %d failed to handle %s", link.system_id, m.get_type())

    # ------------------------------------------------------------------- send
    def emit(self, k: int, data: bytes) -> None:
        self.stats.frames_out += 1
        gate = self.gate
        if gate is not None and gate.active:
            fate = gate.fate(k, DOWNLINK, _frame_msg_id(data))
            if fate is not None:
                for delay_s in fate:
                    if delay_s > 0.0 and self._loop is not None:
                        self._loop.call_later(delay_s, self._send, data)
                    else:
                        self._send_now(data)
                return
        self._send_now(data)

    def emit_frames(self, data: bytes, ends: Sequence[int]) -> bool:
        """Frames data[ends[i-1]:ends[i]] (data[:ends[0]] first) in a batch, packed into
        datagrams as `emit` would pack them one by one; False, sending nothing, while the
        link gate decides frame by frame (the caller then emits each)."""
        gate = self.gate
        if (gate is not None and gate.active) or not self.batching:
            return False
        self.stats.frames_out += len(ends)
        batch, start, i, count = self._batch, 0, 0, len(ends)
        while i < count:
            # The frames from i on that still fit into the datagram being packed.
            j = bisect.bisect_right(ends, start + MAX_BATCH_BYTES - len(batch), i)
            if j == i:
                self.flush()
                j = max(bisect.bisect_right(ends, start + MAX_BATCH_BYTES, i), i + 1)
            batch += data[start:ends[j - 1]]
            start, i = ends[j - 1], j
            if i < count:
                self.flush()
        return True

    def _send_now(self, data: bytes) -> None:
        if self.batching:
            if len(self._batch) + len(data) > MAX_BATCH_BYTES:
                self.flush()
            self._batch += data
            return
        self._send(data)

    def flush(self) -> None:
        """Send the telemetry frames packed since the last flush."""
        if self._batch:
            self._send(bytes(self._batch))
            self._batch.clear()

    def _send(self, data: bytes) -> None:
        sock = self._sock
        if sock is None:
            return
        for addr in self._targets:
            try:
                sock.sendto(data, addr)
            except OSError:  # buffer full, or an unreachable port reported late
                self.stats.send_errors += 1
        self.stats.datagrams_out += 1

    def expire_peers(self, wall_now_s: float) -> None:
        stale = [a for a, t in self._peers.items() if wall_now_s - t > PEER_TIMEOUT_S]
        for addr in stale:
            del self._peers[addr]
        if stale:
            self._refresh_targets()

    def _refresh_targets(self) -> None:
        self._targets = tuple(dict.fromkeys(self._fixed + tuple(self._peers)))
        self.stats.peers = set(self._peers)


def _frame_msg_id(frame: bytes) -> int:
    """The message id of one encoded MAVLink frame (v2: 24 bits at offset 7; v1: offset 5)."""
    if frame[:1] == b"\xfd" and len(frame) >= 10:
        return int.from_bytes(frame[7:10], "little")
    return frame[5] if len(frame) > 5 else -1
