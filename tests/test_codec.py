"""The datagram decoder cuts frames itself and decodes each with pymavlink: frame for frame
the same messages and the same ok/bad counts as pymavlink's robust parser over the whole
datagram (the reference below), on hostile datagrams and on hand-made edge cases."""

from __future__ import annotations

import random

from pymavlink.dialects.v20 import common as mavlink

from emulator.mavlink.codec import _DECODE_ERRORS, DatagramDecoder
from tests.frame_fuzz import FrameFuzzer


class ReferenceDecoder:
    """pymavlink's robust `parse_buffer` over one datagram, nothing carried over."""

    def __init__(self) -> None:
        self._mav = mavlink.MAVLink(None, srcSystem=0, srcComponent=0)
        self._mav.robust_parsing = True
        self.frames_ok = 0
        self.frames_bad = 0

    def decode(self, data: bytes) -> list[mavlink.MAVLink_message]:
        mav = self._mav
        out = []
        try:
            msgs = mav.parse_buffer(data) or []
        except _DECODE_ERRORS:
            self.frames_bad += 1
            msgs = []
        else:
            if mav.buf_len() > 0:
                self.frames_bad += 1
        finally:
            mav.buf = bytearray()
            mav.buf_index = 0
            mav.expected_length = mavlink.HEADER_LEN_V1 + 2
            mav.have_prefix_error = False
        for msg in msgs:
            if msg.get_msgId() < 0:
                self.frames_bad += 1
            else:
                self.frames_ok += 1
                out.append(msg)
        return out


def _same(datagrams: list[bytes]) -> tuple[int, int]:
    fast, reference = DatagramDecoder(), ReferenceDecoder()
    for data in datagrams:
        got = [m.get_msgbuf() for m in fast.decode(data)]
        want = [m.get_msgbuf() for m in reference.decode(data)]
        assert got == want, data.hex()
        assert (fast.frames_ok, fast.frames_bad) == (reference.frames_ok, reference.frames_bad), \
            data.hex()
    return fast.frames_ok, fast.frames_bad


def test_the_decoder_matches_pymavlinks_parser_on_hostile_datagrams() -> None:
    fuzzer = FrameFuzzer(7)
    rng = random.Random(7)
    datagrams = [fuzzer.datagram(rng.randint(1, 12)) for _ in range(3000)]
    ok, bad = _same(datagrams)
    assert ok > 5000 and bad > 5000


def test_the_decoder_matches_pymavlinks_parser_on_edge_cases() -> None:
    mav = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
    v2 = mavlink.MAVLink_ping_message(1, 2, 3, 4).pack(mav)
    mav1 = mavlink.MAVLink(None, srcSystem=255, srcComponent=190, use_native=False)
    v1 = mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 4, 3).pack(mav1, force_mavlink1=True)
    signed = bytearray(v2)
    signed[2] |= mavlink.MAVLINK_IFLAG_SIGNED  # claims a signature it does not carry
    unknown_flags = bytearray(v2)
    unknown_flags[2] = 0x02
    cases = [
        b"", b"\x00", b"\xfd", b"\xfd\x09", b"\xfe", v2, v1, v2 + v1, b"junk" + v2 + b"xx",
        v2[:-1], v2 + v2[:5], bytes(signed), bytes(signed) + bytes(13), bytes(unknown_flags) + v2,
        v2[:1] + bytes([40]) + v2[2:], b"\xfd\xff" + bytes(300), v2[:7] + b"\x0d\x00\x00" + v2[10:],
    ]
    _same(cases)
