"""The one port allocator of the test suite: free loopback ports, never the same one twice
in a test session (so parallel swarms and servers never collide).

Under pytest-xdist every worker is a process of its own with its own record of the ports it
handed out, so the workers share the ports out: worker k of n takes only ports p with
p % n == k. A port one worker handed out (and a swarm binds a moment later) is never the one
another worker is given meanwhile."""

from __future__ import annotations

import os
import socket

__all__ = ["unused_tcp_port", "unused_udp_port"]

_handed_out: set[tuple[int, int]] = set()


def _worker_share() -> tuple[int, int]:
    """(k, n): this process takes the ports p with p % n == k ((0, 1) outside xdist)."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "")
    count = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1") or 1)
    if not worker.startswith("gw") or count <= 1:
        return 0, 1
    return int(worker[2:]) % count, count


def _unused(kind: int, host: str) -> int:
    share, workers = _worker_share()
    for _ in range(100 * workers):
        with socket.socket(socket.AF_INET, kind) as s:
            s.bind((host, 0))
            port = s.getsockname()[1]
        if port % workers == share and (kind, port) not in _handed_out:
            _handed_out.add((kind, port))
            return port
    raise RuntimeError("no unused port found")


def unused_udp_port(host: str = "127.0.0.1") -> int:
    """A UDP port nobody is bound to now, never handed out before in this session."""
    return _unused(socket.SOCK_DGRAM, host)


def unused_tcp_port(host: str = "127.0.0.1") -> int:
    """A TCP port nobody is bound to now, never handed out before in this session."""
    return _unused(socket.SOCK_STREAM, host)
