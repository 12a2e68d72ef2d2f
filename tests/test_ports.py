"""tests/ports.py: the ports handed out to tests are free, never handed out twice, and outside
the kernel's ephemeral range, where a socket bound to port 0 (a swarm's, a client's) could
take one before the test binds it."""

from __future__ import annotations

import random
import socket

import pytest

from tests import ports


def test_ports_are_new_and_outside_the_ephemeral_range() -> None:
    low, high = ports._ephemeral_range()
    assert 0 < low <= high <= 65535
    handed = [ports.unused_udp_port() for _ in range(50)]
    handed_tcp = [ports.unused_tcp_port() for _ in range(50)]
    for group in (handed, handed_tcp):
        assert len(set(group)) == len(group)
        if low - ports.FIRST_PORT >= 1000:
            assert all(ports.FIRST_PORT <= p < low for p in group), group
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", handed[0]))  # handed out, and still free to bind


def test_a_port_someone_holds_is_skipped(monkeypatch: pytest.MonkeyPatch) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as held:
        held.bind(("127.0.0.1", 0))
        busy = held.getsockname()[1]

        class BusyFirst(random.Random):
            def randrange(self, *_: object) -> int:  # type: ignore[override]
                self.calls = getattr(self, "calls", 0) + 1
                return busy if self.calls == 1 else super().randrange(ports.FIRST_PORT, 30000)

        monkeypatch.setattr(ports, "_order", BusyFirst(7))
        monkeypatch.setattr(ports, "_ephemeral_range", lambda: (32768, 60999))
        port = ports.unused_udp_port()
    assert port != busy and ports.FIRST_PORT <= port < 30000
