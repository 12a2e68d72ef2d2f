"""MAVLink FTP, read-only, as PX4 answers it: list a directory, open a file, read it (plain
or burst), end sessions. The file system is virtual: `/log/` holds the vehicle's flight logs
(the same ULogs as the log protocol, `flight_<n>.ulg`), `/metadata/` the component metadata
QGroundControl fetches (the general metadata and the parameter metadata, generated from the
parameter definitions). Every write operation is NAKed (the file system is read-only), every
unknown one with UnknownCommand. `FtpServer.handle` takes one request payload and returns
the reply payloads.
"""

from __future__ import annotations

import struct
from collections.abc import Callable

from emulator.mavlink.component_metadata import metadata_files

__all__ = ["FTP_HEADER_BYTES", "FTP_PAYLOAD_BYTES", "FtpServer", "Op"]

FTP_PAYLOAD_BYTES = 251
FTP_HEADER_BYTES = 12
FTP_DATA_BYTES = FTP_PAYLOAD_BYTES - FTP_HEADER_BYTES
MAX_SESSIONS = 4
LOG_DIRECTORY = "/log/"


class Op:
    NONE, TERMINATE_SESSION, RESET_SESSIONS, LIST_DIRECTORY, OPEN_FILE_RO = 0, 1, 2, 3, 4
    READ_FILE, BURST_READ_FILE = 5, 15
    ACK, NAK = 128, 129


class Err:
    FAIL, INVALID_SESSION, NO_SESSIONS, EOF, UNKNOWN_COMMAND = 1, 4, 5, 6, 7
    FILE_PROTECTED, FILE_NOT_FOUND = 9, 10


_WRITE_OPS = frozenset({6, 7, 8, 9, 10, 11, 12, 13})  # create, write, remove, mkdir, ...


class FtpServer:
    """The FTP server of one vehicle: `files()` lists the virtual files (path -> bytes
    loader) when a directory is listed or a file opened."""

    def __init__(self, log_files: Callable[[], list[bytes]]) -> None:
        self._log_files = log_files
        self._sessions: dict[int, bytes] = {}

    def _files(self, directory: str) -> dict[str, bytes]:
        """The files under `directory` (path -> content); the logs are built only for /log."""
        if directory.startswith(LOG_DIRECTORY):
            return {f"{LOG_DIRECTORY}flight_{i}.ulg": data
                    for i, data in enumerate(self._log_files())}
        return dict(metadata_files())

    def handle(self, request: bytes) -> list[bytes]:
        if len(request) < FTP_HEADER_BYTES:
            return []
        seq, session, op, size, _, _, _, offset = struct.unpack_from("<HBBBBBBI", request)
        data = request[FTP_HEADER_BYTES:FTP_HEADER_BYTES + size]

        def reply(opcode: int, payload: bytes = b"", *, at: int = offset, burst_done: int = 0,
                  reply_seq: int = seq + 1) -> bytes:
            head = struct.pack("<HBBBBBBI", reply_seq & 0xFFFF, session, opcode, len(payload),
                               op, burst_done, 0, at)
            return (head + payload).ljust(FTP_PAYLOAD_BYTES, b"\0")

        def nak(error: int) -> list[bytes]:
            return [reply(Op.NAK, bytes([error]))]

        if op in (Op.TERMINATE_SESSION, Op.RESET_SESSIONS):
            if op == Op.RESET_SESSIONS:
                self._sessions.clear()
            else:
                self._sessions.pop(session, None)
            return [reply(Op.ACK)]
        if op == Op.LIST_DIRECTORY:
            return [self._list(data.split(b"\0")[0].decode("utf-8", "replace"), offset, reply)
                    or reply(Op.NAK, bytes([Err.EOF]))]
        if op == Op.OPEN_FILE_RO:
            path = data.split(b"\0")[0].decode("utf-8", "replace")
            content = self._files(path).get(path)
            if content is None:
                return nak(Err.FILE_NOT_FOUND)
            if len(self._sessions) >= MAX_SESSIONS:
                return nak(Err.NO_SESSIONS)
            session = next(i for i in range(MAX_SESSIONS) if i not in self._sessions)
            self._sessions[session] = content
            return [reply(Op.ACK, struct.pack("<I", len(content)))]
        if op in (Op.READ_FILE, Op.BURST_READ_FILE):
            content = self._sessions.get(session)
            if content is None:
                return nak(Err.INVALID_SESSION)
            if offset >= len(content):
                return nak(Err.EOF)
            if op == Op.READ_FILE:
                return [reply(Op.ACK, content[offset:offset + min(size or FTP_DATA_BYTES,
                                                                   FTP_DATA_BYTES)])]
            chunks = range(offset, len(content), FTP_DATA_BYTES)
            return [reply(Op.ACK, content[at:at + FTP_DATA_BYTES], at=at, reply_seq=seq + 1 + i,
                          burst_done=int(at + FTP_DATA_BYTES >= len(content)))
                    for i, at in enumerate(chunks)]
        if op in _WRITE_OPS:
            return nak(Err.FILE_PROTECTED)
        return nak(Err.UNKNOWN_COMMAND)

    def _list(self, path: str, offset: int, reply: Callable[..., bytes]) -> bytes | None:
        """One ACK with the entries of `path` from index `offset` (None past the end)."""
        directory = path.rstrip("/") + "/"
        files = self._files(directory)
        if directory == "/":
            entries = ["Dlog", *(f"D{name}" for name in sorted({p.split("/")[1] for p in files}))]
        else:
            entries = [f"F{p[len(directory):]}\t{len(data)}" for p, data in sorted(files.items())
                       if p.startswith(directory) and "/" not in p[len(directory):]]
        payload = b""
        for entry in entries[offset:]:
            encoded = entry.encode() + b"\0"
            if len(payload) + len(encoded) > FTP_DATA_BYTES:
                break
            payload += encoded
        return reply(Op.ACK, payload) if payload else None
