"""A minimal ULog writer (PX4's flight log format, version 1): header, flag bits, info,
formats, subscriptions, data rows and logged strings. Only what the emulator's flight logs
need: fixed-size numeric fields, no nested types, no appended data.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence

__all__ = ["ULogWriter"]

_MAGIC = b"ULog\x01\x12\x35"
_VERSION = 1
_TYPES = {"uint64_t": "Q", "int64_t": "q", "uint32_t": "I", "int32_t": "i", "uint16_t": "H",
          "int16_t": "h", "uint8_t": "B", "int8_t": "b", "float": "f", "double": "d",
          "bool": "?"}
LOG_LEVEL_INFO = ord("6")
LOG_LEVEL_WARNING = ord("4")


class ULogWriter:
    """Builds one ULog file in memory; `bytes()` of it is the file."""

    def __init__(self, start_us: int) -> None:
        self._out = bytearray(_MAGIC + bytes([_VERSION]) + struct.pack("<Q", start_us))
        self._message(b"B", bytes(8) + bytes(8) + bytes(24))  # no flags, no appended data
        self._packers: dict[int, struct.Struct] = {}
        self._next_id = 0

    def _message(self, kind: bytes, payload: bytes) -> None:
        self._out += struct.pack("<HB", len(payload), kind[0]) + payload

    def info(self, key: str, value: str) -> None:
        data = value.encode()
        name = f"char[{len(data)}] {key}".encode()
        self._message(b"I", bytes([len(name)]) + name + data)

    def topic(self, name: str, fields: Sequence[tuple[str, str]]) -> int:
        """Define a topic (first field: uint64_t timestamp) and subscribe to it: its id."""
        if fields[0] != ("uint64_t", "timestamp"):
            raise ValueError("a ULog topic starts with uint64_t timestamp")
        text = f"{name}:" + "".join(f"{t} {f};" for t, f in fields)
        self._message(b"F", text.encode())
        msg_id = self._next_id
        self._next_id += 1
        self._message(b"A", struct.pack("<BH", 0, msg_id) + name.encode())
        self._packers[msg_id] = struct.Struct("<" + "".join(_TYPES[t] for t, _ in fields))
        return msg_id

    def data(self, msg_id: int, *values: float) -> None:
        self._message(b"D", struct.pack("<H", msg_id) + self._packers[msg_id].pack(*values))

    def log(self, timestamp_us: int, text: str, level: int = LOG_LEVEL_INFO) -> None:
        self._message(b"L", struct.pack("<BQ", level, timestamp_us) + text.encode())

    def __bytes__(self) -> bytes:
        return bytes(self._out)
