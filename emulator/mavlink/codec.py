"""MAVLink v2 framing: an encoder per (system, component) and a datagram decoder.

pymavlink (common dialect, MAVLink 2, fastcrc) does the byte work. A UDP datagram is
decoded on its own: bytes that do not form valid frames are counted and dropped, and no
partial frame is carried into the next datagram.
"""

from __future__ import annotations

import os
import struct

os.environ.setdefault("MAVLINK20", "1")

from pymavlink.dialects.v20 import common as mavlink

__all__ = ["DatagramDecoder", "Encoder", "mavlink"]

_DECODE_ERRORS = (
    mavlink.MAVError, struct.error, ValueError, IndexError, KeyError, TypeError,
    UnicodeDecodeError, OverflowError,
)


class Encoder:
    """Packs messages as one (system id, component id), with its own sequence numbers."""

    __slots__ = ("_mav",)

    def __init__(self, system_id: int, component_id: int) -> None:
        if not 1 <= system_id <= 255 or not 0 <= component_id <= 255:
            raise ValueError(f"invalid MAVLink address {system_id}/{component_id}")
        self._mav = mavlink.MAVLink(None, srcSystem=system_id, srcComponent=component_id)

    @property
    def system_id(self) -> int:
        return self._mav.srcSystem

    @property
    def component_id(self) -> int:
        return self._mav.srcComponent

    def pack(self, message: mavlink.MAVLink_message) -> bytes:
        buf = message.pack(self._mav)
        self._mav.seq = (self._mav.seq + 1) & 0xFF
        return buf


class DatagramDecoder:
    """Turns datagrams into messages; counts what it had to drop."""

    def __init__(self) -> None:
        self._mav = mavlink.MAVLink(None, srcSystem=0, srcComponent=0)
        self._mav.robust_parsing = True
        self.frames_ok = 0
        self.frames_bad = 0

    def decode(self, data: bytes) -> list[mavlink.MAVLink_message]:
        mav = self._mav
        out: list[mavlink.MAVLink_message] = []
        try:
            msgs = mav.parse_buffer(data) or []
        except _DECODE_ERRORS:
            self.frames_bad += 1
            msgs = []
        else:
            if mav.buf_len() > 0:  # a frame cut short by the end of the datagram
                self.frames_bad += 1
        finally:
            mav.buf = bytearray()
            mav.buf_index = 0
            mav.expected_length = mavlink.HEADER_LEN_V1 + 2
            mav.have_prefix_error = False
        for msg in msgs:
            if msg.get_msgId() < 0:  # MAVLink_bad_data
                self.frames_bad += 1
            else:
                self.frames_ok += 1
                out.append(msg)
        return out
