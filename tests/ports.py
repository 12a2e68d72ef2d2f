"""The one port allocator of the test suite: free loopback ports, never the same one twice
in a test session (so parallel swarms and servers never collide)."""

from __future__ import annotations

import socket

__all__ = ["unused_tcp_port", "unused_udp_port"]

_handed_out: set[tuple[int, int]] = set()


def _unused(kind: int, host: str) -> int:
    for _ in range(100):
        with socket.socket(socket.AF_INET, kind) as s:
            s.bind((host, 0))
            port = s.getsockname()[1]
        if (kind, port) not in _handed_out:
            _handed_out.add((kind, port))
            return port
    raise RuntimeError("no unused port found")


def unused_udp_port(host: str = "127.0.0.1") -> int:
    """A UDP port nobody is bound to now, never handed out before in this session."""
    return _unused(socket.SOCK_DGRAM, host)


def unused_tcp_port(host: str = "127.0.0.1") -> int:
    """A TCP port nobody is bound to now, never handed out before in this session."""
    return _unused(socket.SOCK_STREAM, host)
