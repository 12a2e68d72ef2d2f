"""UDP transport: moves datagrams between one socket and one network protocol, nothing else.

One `UdpEndpoint` owns one non-blocking socket and drives the `NetworkProtocol` of the
vehicles behind it (emulator.mavlink.protocol, which decodes, routes, answers and applies link
faults without I/O). Every readable datagram is drained at once when the socket becomes
readable; what the protocol has to send goes out at the end of the event loop's turn (its
`on_pending` hook schedules that), and its timer (delayed frames of a faulty link) is driven
with `loop.call_later`.
"""

from __future__ import annotations

import asyncio
import socket
from collections.abc import Callable

from emulator.mavlink.protocol import Address, LinkStats, NetworkProtocol

__all__ = ["RECV_BYTES", "UdpEndpoint"]

RECV_BYTES = 65535


class UdpEndpoint:
    """One UDP socket serving `protocol`."""

    def __init__(self, protocol: NetworkProtocol, wall_clock: Callable[[], float],
                 on_receive: Callable[[], None]) -> None:
        self.protocol = protocol
        self._wall_clock = wall_clock
        self._on_receive = on_receive
        self._sock: socket.socket | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._transmit_scheduled = False
        self._timer: asyncio.TimerHandle | None = None
        self._timer_at: float | None = None

    @property
    def stats(self) -> LinkStats:
        return self.protocol.stats

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
        self.protocol.on_pending = self._schedule_transmit
        self.protocol.open()

    @property
    def is_open(self) -> bool:
        return self._sock is not None

    @property
    def local_address(self) -> Address:
        assert self._sock is not None
        return self._sock.getsockname()[:2]

    def close(self) -> None:
        self.protocol.close()
        self.protocol.on_pending = None
        if self._timer is not None:
            self._timer.cancel()
            self._timer = self._timer_at = None
        if self._sock is not None:
            if self._loop is not None and not self._loop.is_closed():
                self._loop.remove_reader(self._sock.fileno())
            self._sock.close()
            self._sock = None

    def _drain(self) -> None:
        sock = self._sock
        received = False
        while sock is not None:
            try:
                data, addr = sock.recvfrom(RECV_BYTES)
            except (BlockingIOError, InterruptedError):
                break
            except OSError:  # ICMP port unreachable from a ground-station port nobody opened
                self.protocol.stats.send_errors += 1
                continue
            received = True
            self.protocol.receive_datagram(data, addr, self._wall_clock())
            sock = self._sock
        if received:
            self.transmit()
            self._on_receive()

    def _schedule_transmit(self) -> None:
        if not self._transmit_scheduled and self._loop is not None:
            self._transmit_scheduled = True
            self._loop.call_soon(self.transmit)

    def transmit(self) -> None:
        """Send what the protocol has queued, and set its timer."""
        self._transmit_scheduled = False
        sock = self._sock
        if sock is None:
            return
        now = self._wall_clock()
        delivered = self.protocol.handle_timer(now)  # a delayed command due by now
        for data, addr in self.protocol.datagrams_to_send(now):
            try:
                sock.sendto(data, addr)
            except OSError:  # buffer full, or an unreachable port reported late
                self.protocol.stats.send_errors += 1
        self._set_timer()
        if delivered:
            self._on_receive()

    def _set_timer(self) -> None:
        at = self.protocol.next_timer()
        if at == self._timer_at or self._loop is None:
            return
        if self._timer is not None:
            self._timer.cancel()
        self._timer_at = at
        self._timer = None if at is None else self._loop.call_later(
            max(0.0, at - self._wall_clock()), self._on_timer)

    def _on_timer(self) -> None:
        self._timer = self._timer_at = None
        if self._sock is None:
            return
        self.transmit()
