"""The one port allocator of the test suite: free loopback ports, never the same one twice
in a test session (so parallel swarms and servers never collide).

Under pytest-xdist every worker is a process of its own, so the ports handed out are also
written to a registry file of the test run (named after xdist's run id, locked while read
and written): a port one worker handed out (and a swarm binds a moment later) is never the
one another worker is given meanwhile. Ports come from outside the kernel's ephemeral range,
so no socket that binds port 0 (a swarm's, a client's) can take one in between.
"""

from __future__ import annotations

import fcntl
import functools
import itertools
import os
import random
import socket
import tempfile
from collections.abc import Iterator
from pathlib import Path

__all__ = ["drop_registry", "unused_tcp_port", "unused_udp_port"]

FIRST_PORT = 20000  # below: Ray's worker ports (10002-19999) and well-known services
_handed_out: set[tuple[int, int]] = set()
_order = random.Random(os.getpid())  # each worker tries the ports in an order of its own


def _registry() -> Path | None:
    """The file the xdist workers of this run share (None outside xdist)."""
    run = os.environ.get("PYTEST_XDIST_TESTRUNUID")
    return Path(tempfile.gettempdir()) / f"mavswarm-test-ports-{run}" if run else None


def _claim(kind: int, port: int) -> bool:
    """Hand `port` out unless this run already did, in this process or another worker."""
    if (kind, port) in _handed_out:
        return False
    registry = _registry()
    if registry is not None:
        key = f"{kind}:{port}"
        with registry.open("a+") as f:
            fcntl.flock(f, fcntl.LOCK_EX)
            f.seek(0)
            if key in f.read().split():
                return False
            f.write(f"{key}\n")
    _handed_out.add((kind, port))
    return True


def drop_registry() -> None:
    """Remove the run's registry (a worker whose session ended: a worker still running then
    starts a new one, and its own ports it remembers itself)."""
    registry = _registry()
    if registry is not None:
        registry.unlink(missing_ok=True)


@functools.cache
def _ephemeral_range() -> tuple[int, int]:
    """The ports the kernel picks from for a socket bound to port 0 (or never bound)."""
    try:
        low, high = map(int, Path("/proc/sys/net/ipv4/ip_local_port_range").read_text().split())
    except (OSError, ValueError):
        return 32768, 60999  # Linux's default
    return low, high


def _candidates() -> Iterator[int]:
    """Ports to try, in an order of this process's own: those between FIRST_PORT and the
    kernel's ephemeral range, which no socket bound to port 0 is ever given (a swarm's own
    socket, a client's, another worker's server), so a port handed out stays free until its
    user binds it; where the range leaves none, the kernel's own pick."""
    low = _ephemeral_range()[0]
    if low - FIRST_PORT >= 1000:
        while True:
            yield _order.randrange(FIRST_PORT, low)
    while True:
        yield 0


def _unused(kind: int, host: str) -> int:
    for port in itertools.islice(_candidates(), 1000):
        with socket.socket(socket.AF_INET, kind) as s:
            try:
                s.bind((host, port))
            except OSError:  # someone is bound to it now
                continue
            port = s.getsockname()[1]
        if _claim(kind, port):
            return port
    raise RuntimeError("no unused port found")


def unused_udp_port(host: str = "127.0.0.1") -> int:
    """A UDP port nobody is bound to now, never handed out before in this session."""
    return _unused(socket.SOCK_DGRAM, host)


def unused_tcp_port(host: str = "127.0.0.1") -> int:
    """A TCP port nobody is bound to now, never handed out before in this session."""
    return _unused(socket.SOCK_STREAM, host)
