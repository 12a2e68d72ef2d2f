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


_V1, _V2 = mavlink.PROTOCOL_MARKER_V1, mavlink.PROTOCOL_MARKER_V2
_SIGNED = mavlink.MAVLINK_IFLAG_SIGNED
_SIGNATURE_BYTES = mavlink.MAVLINK_SIGNATURE_BLOCK_LEN


class DatagramDecoder:
    """Turns datagrams into messages; counts what it had to drop.

    Frames are cut out of a datagram here and each is decoded by pymavlink's `decode`, with
    the outcome of pymavlink's robust parser (`parse_buffer` with `robust_parsing`) frame for
    frame, without its per-byte buffer bookkeeping (tests/test_codec.py compares the two):
    a run of bytes that starts no frame is one bad frame, a frame with unknown incompatibility
    flags, a bad checksum or length is one bad frame, and a frame cut short by the end of the
    datagram is one more. An unexpected error while decoding drops the whole datagram as one
    bad frame.
    """

    def __init__(self) -> None:
        self._mav = mavlink.MAVLink(None, srcSystem=0, srcComponent=0)
        self._mav.robust_parsing = True
        self.frames_ok = 0
        self.frames_bad = 0

    def decode(self, data: bytes) -> list[mavlink.MAVLink_message]:
        try:
            out, bad = self._split(data)
        except _DECODE_ERRORS:
            self.frames_bad += 1
            return []
        self.frames_ok += len(out)
        self.frames_bad += bad
        return out

    def _split(self, data: bytes) -> tuple[list[mavlink.MAVLink_message], int]:
        decode = self._mav.decode
        out: list[mavlink.MAVLink_message] = []
        bad = 0
        end = len(data)
        i = 0
        while i < end:
            magic = data[i]
            if magic != _V1 and magic != _V2:  # bytes that start no frame: one bad frame
                i += 1
                while i < end and data[i] != _V1 and data[i] != _V2:
                    i += 1
                bad += 1
                continue
            if end - i < 3:
                return out, bad + 1  # cut short
            length, flags = data[i + 1], data[i + 2]
            if magic == _V2:
                size = length + mavlink.HEADER_LEN_V2 + 2
                if flags & _SIGNED:
                    size += _SIGNATURE_BYTES
            else:
                size = length + mavlink.HEADER_LEN_V1 + 2
            if end - i < size:
                return out, bad + 1  # cut short
            frame = bytearray(data[i:i + size])
            i += size
            if magic == _V2 and flags & ~_SIGNED:
                bad += 1  # incompatibility flags this decoder does not know
                continue
            try:
                m = decode(frame)
            except mavlink.MAVError:
                bad += 1
                continue
            if m.get_msgId() < 0:  # MAVLink_bad_data
                bad += 1
            else:
                out.append(m)
        return out, bad
