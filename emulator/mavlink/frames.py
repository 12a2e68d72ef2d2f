"""MAVLink 2 framing of many messages at once, on numpy arrays.

The batched counterpart of pymavlink's `MAVLink_message._pack` (unsigned MAVLink 2): a
message type's payloads are rows of a numpy structured array laid out exactly as pymavlink's
`struct` format packs them (fields in wire order, little-endian, no padding). `frame_batch`
frames rows of any number of message types together: it drops each payload's trailing zero
bytes (keeping at least one), writes the 10-byte header (sequence, system and component id
per row), and computes the X.25 CRC (CRC-16/MCRF4XX over header[1:] + payload + CRC_EXTRA)
for every row at once, two bytes per table look-up.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from emulator.mavlink.codec import mavlink

__all__ = ["FramePart", "Frames", "MessageLayout", "frame_batch", "x25_crc"]

STX_V2 = 0xFD
HEADER_LEN = 10
CRC_LEN = 2
_STRUCT_CODES = {
    "B": "u1", "b": "i1", "H": "<u2", "h": "<i2", "I": "<u4", "i": "<i4",
    "Q": "<u8", "q": "<i8", "f": "<f4", "d": "<f8",
}


def _byte_table() -> np.ndarray:
    """CRC-16/MCRF4XX (reflected polynomial 0x8408) of one byte from register 0."""
    table = np.arange(256, dtype=np.uint32)
    for _ in range(8):
        table = np.where(table & 1, (table >> 1) ^ 0x8408, table >> 1)
    return table.astype(np.uint16)


_T8 = _byte_table()


def _word_table() -> np.ndarray:
    """The register after two bytes, as a function of (register ^ the two bytes, LE)."""
    w = np.arange(1 << 16, dtype=np.uint32)
    t8 = _T8.astype(np.uint32)
    c1 = (w >> 8) ^ t8[w & 0xFF]
    return ((c1 >> 8) ^ t8[c1 & 0xFF]).astype(np.uint16)


_T16 = _word_table()


def x25_crc(data: bytes, crc: int = 0xFFFF) -> int:
    """The MAVLink checksum of `data` (one message; for tests and small jobs)."""
    for b in data:
        crc = (crc >> 8) ^ int(_T8[(crc ^ b) & 0xFF])
    return crc


@dataclass(frozen=True, slots=True)
class MessageLayout:
    """Wire layout of one message type, read from its pymavlink class."""

    msg_id: int
    name: str
    crc_extra: int
    dtype: np.dtype
    fieldnames: tuple[str, ...]  # constructor (definition) order

    @classmethod
    def of(cls, message_class: type[mavlink.MAVLink_message]) -> MessageLayout:
        fmt = message_class.unpacker.format
        tokens = re.findall(r"(\d*)([a-zA-Z])", fmt.lstrip("<"))
        names = message_class.ordered_fieldnames
        if len(tokens) != len(names):
            raise ValueError(f"cannot read the layout of {message_class.msgname}: {fmt}")
        fields: list[tuple] = []
        for name, (count, code) in zip(names, tokens, strict=True):
            n = int(count or 1)
            if code in ("s", "c"):
                fields.append((name, f"S{n}"))
            elif n == 1:
                fields.append((name, _STRUCT_CODES[code]))
            else:
                fields.append((name, _STRUCT_CODES[code], (n,)))
        dtype = np.dtype(fields)
        if dtype.itemsize != message_class.unpacker.size:
            raise ValueError(f"layout of {message_class.msgname} has padding")
        return cls(message_class.id, message_class.msgname, message_class.crc_extra, dtype,
                   tuple(message_class.fieldnames))

    def records(self, n: int, values: Sequence[object]) -> np.ndarray:
        """n payload records from values in the pymavlink constructor's order (arrays of n,
        scalars, or for array fields arrays of shape (n, len)); fields not given are 0, as
        pymavlink's extension defaults."""
        rec = np.zeros(n, dtype=self.dtype)
        for name, value in zip(self.fieldnames, values, strict=False):
            rec[name] = value
        return rec


@dataclass(frozen=True, slots=True)
class FramePart:
    """Rows of one message type: payload records and each row's sender and sequence."""

    layout: MessageLayout
    records: np.ndarray
    system_ids: np.ndarray
    component_id: int
    sequences: np.ndarray


@dataclass(frozen=True, slots=True)
class Frames:
    """Framed rows, concatenated: row i is data[ends[i] - lengths[i]:ends[i]]."""

    data: bytes
    ends: np.ndarray
    lengths: np.ndarray

    def __len__(self) -> int:
        return len(self.ends)

    def frame(self, i: int) -> bytes:
        end = int(self.ends[i])
        return self.data[end - int(self.lengths[i]):end]


def _payload_lengths(payload: np.ndarray) -> np.ndarray:
    """Bytes kept of each row: up to its last non-zero byte, at least one."""
    nonzero = payload != 0
    nonzero[:, 0] = True  # an all-zero payload keeps its first byte
    return payload.shape[1] - nonzero[:, ::-1].argmax(axis=1)


def frame_batch(parts: Sequence[FramePart], order: np.ndarray | None = None) -> Frames:
    """Every row of `parts`, framed as pymavlink frames it, in order, or in the order of the
    row indices `order` (a permutation of all the rows of `parts`) when given."""
    parts = [p for p in parts if len(p.records)]
    if not parts:
        return Frames(b"", np.zeros(0, np.int64), np.zeros(0, np.int64))
    rows = sum(len(p.records) for p in parts)
    widest = max(p.layout.dtype.itemsize for p in parts)
    width = HEADER_LEN + widest + CRC_LEN + 1
    # Every byte a frame keeps is written below (bytes past a row's CRC are never read).
    m = np.empty((rows, width), dtype=np.uint8)
    m[:, 0] = STX_V2
    m[:, 2:4] = 0  # incompatibility and compatibility flags
    lengths = np.empty(rows, dtype=np.int64)
    extra = np.empty(rows, dtype=np.uint8)
    r0 = 0
    for p in parts:
        size = p.layout.dtype.itemsize
        r1 = r0 + len(p.records)
        block = m[r0:r1]
        payload = np.ascontiguousarray(p.records).view(np.uint8).reshape(r1 - r0, size)
        block[:, HEADER_LEN:HEADER_LEN + size] = payload
        lengths[r0:r1] = _payload_lengths(payload)
        block[:, 4] = p.sequences
        block[:, 5] = p.system_ids
        msg_id = p.layout.msg_id
        block[:, 6:10] = (p.component_id, msg_id & 0xFF, (msg_id >> 8) & 0xFF, msg_id >> 16)
        extra[r0:r1] = p.layout.crc_extra
        r0 = r1
    m[:, 1] = lengths
    at = np.arange(rows)
    tail = HEADER_LEN + lengths
    m[at, tail] = extra
    # The checksum covers bytes 1 .. tail (header after STX, payload, CRC_EXTRA), two bytes
    # per step. With the rows longest first, step j updates only the rows that have a word j:
    # a prefix, which stops moving once a row's words are done.
    words = tail // 2
    n_words = int(words.max())
    longest = np.argsort(-words, kind="stable")
    w = m[longest, 1:1 + 2 * n_words].view("<u2").T.copy()
    active = np.searchsorted(-words[longest], -np.arange(n_words), side="left").tolist()
    crc = np.full(rows, 0xFFFF, dtype=np.uint16)
    mixed = np.empty(rows, dtype=np.uint16)
    take, xor = _T16.take, np.bitwise_xor
    for j, count in enumerate(active):
        xor(crc[:count], w[j, :count], out=mixed[:count])
        take(mixed[:count], out=crc[:count])
    state = np.empty(rows, dtype=np.uint16)
    state[longest] = crc
    odd = (tail & 1).astype(bool)
    if odd.any():
        last = m[at, 1 + 2 * words]
        state = np.where(odd, (state >> 8) ^ _T8[(state ^ last) & 0xFF], state)
    m[at, tail] = state & 0xFF
    m[at, tail + 1] = state >> 8
    frame_len = tail + CRC_LEN
    if order is not None:
        m, frame_len = m[order], frame_len[order]
    keep = np.arange(width) < frame_len[:, None]
    return Frames(m[keep].tobytes(), np.cumsum(frame_len), frame_len)
