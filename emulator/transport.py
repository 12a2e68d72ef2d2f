"""UDP transport: moves MAVLink datagrams between sockets and vehicle links, nothing else.

One `UdpEndpoint` owns one socket and the vehicles behind it (all of them in the default
shared topology, one each in per-vehicle mode). Incoming frames are routed by
`target_system`; outgoing frames go to the configured ground-station ports and to every peer
that has talked to the socket in the last `PEER_TIMEOUT_S` (so `udpout://` clients work).
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

from emulator.mavlink.codec import DatagramDecoder
from emulator.mavlink.vehicle_link import VehicleLink

__all__ = ["PEER_TIMEOUT_S", "LinkStats", "UdpEndpoint"]

PEER_TIMEOUT_S = 10.0
Address = tuple[str, int]
log = logging.getLogger("mavswarm.transport")


@dataclass(slots=True)
class LinkStats:
    datagrams_in: int = 0
    datagrams_out: int = 0
    unroutable: int = 0
    send_errors: int = 0
    handler_errors: int = 0
    peers: set[Address] = field(default_factory=set)


class UdpEndpoint(asyncio.DatagramProtocol):
    """One UDP socket serving the vehicles in `links` (system id -> link)."""

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
        self.transport: asyncio.DatagramTransport | None = None

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = transport  # type: ignore[assignment]

    def connection_lost(self, exc: Exception | None) -> None:
        self.transport = None

    def error_received(self, exc: Exception) -> None:
        # ICMP port unreachable from a ground-station port nobody listens on: harmless.
        self.stats.send_errors += 1

    @property
    def local_address(self) -> Address:
        assert self.transport is not None
        return self.transport.get_extra_info("sockname")[:2]

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
                link = links.get(target)
                if link is None:
                    self.stats.unroutable += 1
                else:
                    self._deliver(link, m, now)
        self._on_receive()

    def _deliver(self, link: VehicleLink, m, now: float) -> None:
        # The I/O edge: a handler bug is logged with its traceback and counted, and the
        # socket keeps serving every other vehicle instead of closing.
        try:
            link.handle(m, now)
        except Exception:
            self.stats.handler_errors += 1
            log.exception("vehicle %d failed to handle %s", link.system_id, m.get_type())

    def emit(self, _k: int, data: bytes) -> None:
        transport = self.transport
        if transport is None:
            return
        for addr in self._targets:
            transport.sendto(data, addr)
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

    def close(self) -> None:
        if self.transport is not None:
            self.transport.close()
