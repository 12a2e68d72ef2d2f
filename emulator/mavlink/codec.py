"""MAVLink v2 framing: an encoder per (system, component) and a datagram decoder.

pymavlink (common dialect, MAVLink 2, fastcrc) does the byte work. A UDP datagram is
decoded on its own: bytes that do not form valid frames are counted and dropped, and no
partial frame is carried into the next datagram.
"""

from __future__ import annotations

import os
import struct

import numpy as np

os.environ.setdefault("MAVLINK20", "1")

from pymavlink.dialects.v20 import common as mavlink

__all__ = ["DatagramDecoder", "Encoder", "mavlink"]

_DECODE_ERRORS = (
    mavlink.MAVError, struct.error, ValueError, IndexError, KeyError, TypeError,
    UnicodeDecodeError, OverflowError,
)


class Encoder:
    """Packs messages as one (system id, component id), with its own sequence numbers.

    `share_sequence` moves the sequence number into a slot of an array that a batched
    sender (emulator.mavlink.telemetry) also draws from, so both count one sequence.
    """

    __slots__ = ("_mav", "_seq_slot", "_seqs")

    def __init__(self, system_id: int, component_id: int) -> None:
        if not 1 <= system_id <= 255 or not 0 <= component_id <= 255:
            raise ValueError(f"invalid MAVLink address {system_id}/{component_id}")
        self._mav = mavlink.MAVLink(None, srcSystem=system_id, srcComponent=component_id)
        self._seqs: np.ndarray | None = None
        self._seq_slot = 0

    def share_sequence(self, sequences: np.ndarray, slot: int) -> None:
        """Count this encoder's sequence in `sequences[slot]` (a uint8 array) from now on."""
        sequences[slot] = self._mav.seq
        self._seqs, self._seq_slot = sequences, slot

    @property
    def system_id(self) -> int:
        return self._mav.srcSystem

    @property
    def component_id(self) -> int:
        return self._mav.srcComponent

    def pack(self, message: mavlink.MAVLink_message) -> bytes:
        mav, seqs = self._mav, self._seqs
        if seqs is not None:
            mav.seq = int(seqs[self._seq_slot])
        buf = message.pack(mav)
        mav.seq = (mav.seq + 1) & 0xFF
        if seqs is not None:
            seqs[self._seq_slot] = mav.seq
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
