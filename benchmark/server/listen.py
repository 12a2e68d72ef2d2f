"""The TCP socket a server of mavswarm listens on, opened before the server starts, so that
a busy port or an address that is not this machine's is one clear OSError, not a server's
startup failure."""

from __future__ import annotations

import socket

__all__ = ["listen_socket"]


def listen_socket(host: str, port: int) -> socket.socket:
    """A TCP socket bound to host:port (port 0: a free one); OSError naming both and why."""
    if not 0 <= port <= 65535:
        raise OSError(f"cannot listen on port {port}: a TCP port is 0 to 65535")
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM,
                                   flags=socket.AI_PASSIVE)
    except (socket.gaierror, UnicodeError) as error:
        raise OSError(f"cannot listen on {host}:{port}: unknown address ({error})") from None
    family, kind, proto, _, address = infos[0]
    sock = socket.socket(family, kind, proto)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(address)
    except OSError as error:
        sock.close()
        why = error.strerror or str(error)
        raise OSError(f"cannot listen on {host}:{port}: {why.lower()}") from None
    return sock
