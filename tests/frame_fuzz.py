"""A seeded generator of hostile MAVLink datagrams, cheap enough for millions of frames.

The suite's one MAVLink frame fuzzer (tests/test_fuzz.py over real UDP, tests/memory_fuzz.py
in memory, tests/test_codec.py, perf/protocol_fuzz.py); its values come from
tests/mavlink_values.py, which the Hypothesis strategies share.

A corpus of valid frames is encoded once with pymavlink: every message type a vehicle handles
(and a few it ignores), with random field values that are often absurd (NaN, infinities,
extreme integers, garbage strings, unknown commands, frames and masks) and sometimes
meaningful (positions near the origin, sensible altitudes and velocities, modes), plus
commands that make vehicles move. Each frame drawn from it is then sent as it is or mutated
at the byte level: its payload scrambled or resized with the checksum made valid again (a
valid frame carrying absurd values), its message id changed to another handled type (checksum
valid) or to one nobody knows, bits flipped, bytes inserted or deleted, header flags set,
truncated, its checksum broken, its length byte changed, or replaced by junk. Several frames
go in one datagram (`datagram`), or a mixed one with duplicates and junk between frames
(`mixed_datagram`). The same seed gives the same datagrams.

State-changing traffic that would make a vehicle unfit to fly afterwards by design (failure
injection and its parameters, the simulated battery endurance) is left out: the storm must
not break a vehicle, and a vehicle told to fail is not broken.
"""

from __future__ import annotations

import itertools
import math
import random
import struct
from collections import Counter

from pymavlink.dialects.v20 import common as mavlink

from emulator.geo import DEFAULT_ORIGIN
from mavlink_vocabulary import MavCmd
from tests.mavlink_values import (
    ALT0_M,
    COMMANDS,
    FAULT_PARAMS,
    INT_RANGES,
    LAT0_E7,
    LON0_E7,
    PARAM_NAMES,
    SPECIAL_FLOATS,
    int_edges,
)

__all__ = ["FAULT_PARAMS", "MUTATIONS", "READ_ONLY", "FrameFuzzer"]

# weights of the message types in the corpus
TYPES = {
    "COMMAND_LONG": 18, "COMMAND_INT": 10, "PARAM_SET": 10, "PARAM_REQUEST_READ": 4,
    "PARAM_REQUEST_LIST": 0.05, "MISSION_COUNT": 5, "MISSION_ITEM_INT": 9, "MISSION_ITEM": 4,
    "MISSION_REQUEST_LIST": 2, "MISSION_REQUEST_INT": 3, "MISSION_REQUEST": 2,
    "MISSION_CLEAR_ALL": 1, "MISSION_SET_CURRENT": 3, "SET_POSITION_TARGET_LOCAL_NED": 8,
    "SET_POSITION_TARGET_GLOBAL_INT": 5, "SET_ATTITUDE_TARGET": 3, "PING": 2, "TIMESYNC": 1,
    "FILE_TRANSFER_PROTOCOL": 2, "REQUEST_DATA_STREAM": 1, "HEARTBEAT": 1, "MISSION_ACK": 1,
    "SET_MODE": 1,
}
# What may reach a vehicle as a broadcast without changing it: requests.
READ_ONLY = frozenset({
    "PARAM_REQUEST_READ", "PARAM_REQUEST_LIST", "MISSION_REQUEST_LIST",
    "MISSION_REQUEST_INT", "MISSION_REQUEST", "PING", "REQUEST_DATA_STREAM",
    "FILE_TRANSFER_PROTOCOL", "MISSION_ACK",
})
LAT0, LON0 = LAT0_E7, LON0_E7
# (mutation, weight): what happens to a frame drawn from the corpus
MUTATIONS = (("valid", 40), ("scrambled", 15), ("truncated", 10), ("bad_crc", 10),
             ("bad_length", 10), ("unknown_id", 10), ("junk", 5), ("bit_flips", 6),
             ("spliced", 6), ("resized", 5), ("other_type", 5), ("header_flags", 4))
HEADER_V2 = 10
CORPUS_SIZE = 8192
UNKNOWN_IDS = (3, 9, 13, 14, 300, 9999, 60000, 0xFFFFFF)  # ids the dialect does not define
DRIVING_EVERY = 10  # one corpus frame in this many is a command that makes vehicles move


class FrameFuzzer:
    """Seeded datagrams for vehicles `systems` (system ids); see the module docstring."""

    def __init__(self, seed: int, systems: tuple[int, ...] = (1, 2, 3)) -> None:
        self.rng = random.Random(seed)
        self.systems = systems
        self.mav = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
        self._classes = {name: mavlink.mavlink_map[getattr(mavlink, f"MAVLINK_MSG_ID_{name}")]
                         for name in TYPES}
        self._names = list(TYPES)
        weights = [TYPES[n] for n in self._names]
        self.corpus = [self._frame(self._classes[name])
                       for name in self.rng.choices(self._names, weights, k=CORPUS_SIZE)]
        for i in range(0, CORPUS_SIZE, DRIVING_EVERY):  # commands that make vehicles move
            self.corpus[i] = self._driving_command()
        self._kinds = [m for m, _ in MUTATIONS]
        self._cumulative = list(itertools.accumulate(w for _, w in MUTATIONS))
        self.counts: Counter[str] = Counter()

    # ------------------------------------------------------------ field values
    def _float(self) -> float:
        rng = self.rng
        r = rng.random()
        if r < 0.45:
            return rng.choice(SPECIAL_FLOATS)
        if r < 0.75:
            return rng.uniform(-200.0, 200.0)
        if r < 0.9:
            return rng.uniform(-1e9, 1e9)
        return struct.unpack("<f", rng.getrandbits(32).to_bytes(4, "little"))[0]

    def _int(self, ftype: str) -> int:
        lo, hi = INT_RANGES[ftype]
        rng = self.rng
        r = rng.random()
        if r < 0.3:
            return rng.choice(int_edges(ftype))
        if r < 0.6:
            return rng.randint(max(lo, -5), min(hi, 10))
        return rng.randint(lo, hi)

    def _value(self, name: str, ftype: str, length: int, type_name: str) -> object:
        rng = self.rng
        if ftype == "char":
            if name == "param_id" and rng.random() < 0.75:
                return rng.choice(PARAM_NAMES)
            return bytes(rng.getrandbits(8) for _ in range(rng.randint(0, length)))
        if length:
            if ftype in INT_RANGES:
                return [self._int(ftype) for _ in range(length)]
            return [self._float() for _ in range(length)]
        special = {
            "target_system": lambda: rng.choice([*self.systems, *self.systems, 0, 77, 255]),
            "target_component": lambda: rng.choice([0, 1, 1, 1, 100, 190, rng.randint(0, 255)]),
            "command": lambda: rng.choice(COMMANDS) if rng.random() < 0.9
            else rng.randint(0, 65535),
            "seq": lambda: rng.randint(0, 6), "count": lambda: rng.randint(0, 6),
            "mission_type": lambda: rng.choice([0, 0, 0, 1, 2, 255]),
            "frame": lambda: rng.choice([0, 1, 2, 3, 5, 6, 7, 8, 9, 10, 11, 12]),
            "coordinate_frame": lambda: rng.choice([0, 1, 3, 5, 6, 7, 8, 9, 10, 11, 12]),
            "param_type": lambda: rng.choice([6, 9, 9, 1, 2, 3, 4, 5, 10]),
            "type_mask": lambda: rng.choice([0x9F8, 0xDC7, 0xDFF, 0, 0xFFFF, 0x7, 0x38]),
            # command parameters that mean something: arm/disarm, PX4 modes and sub modes
            "param1": lambda: rng.choice([0.0, 1.0, 1.0]),
            "param2": lambda: rng.choice([4.0, 6.0, 3.0, 0.0]),
            "param3": lambda: rng.choice([3.0, 4.0, 1.0]),
            "x": lambda: LAT0 + rng.randint(-5000, 5000), "lat_int": lambda: LAT0,
            "y": lambda: LON0 + rng.randint(-5000, 5000), "lon_int": lambda: LON0,
        }
        if name in special and rng.random() < (0.3 if name.startswith("param") else 0.8):
            value = special[name]()
            if ftype in INT_RANGES:
                lo, hi = INT_RANGES[ftype]
                return min(max(int(value), lo), hi)
            return float(value)
        if ftype in INT_RANGES:
            return self._int(ftype)
        return self._meaningful_float(name, type_name)

    def _meaningful_float(self, name: str, type_name: str) -> float:
        """Now and then a float that gets past the range checks: a position near the
        origin, a sensible altitude or velocity; otherwise any float."""
        rng = self.rng
        if type_name in ("COMMAND_LONG", "MISSION_ITEM") and rng.random() < 0.5 and \
                name in ("param5", "param6", "x", "y"):
            lat = name in ("param5", "x")
            base = DEFAULT_ORIGIN.latitude_deg if lat else DEFAULT_ORIGIN.longitude_deg
            return base + rng.uniform(-0.002, 0.002)
        if name in ("z", "alt", "param7") and rng.random() < 0.5:
            return rng.choice([rng.uniform(0, 150), ALT0_M + rng.uniform(-20, 150)])
        if name in ("vx", "vy", "vz") and rng.random() < 0.5:
            return rng.uniform(-60.0, 60.0)
        return self._float()

    def _frame(self, cls: type[mavlink.MAVLink_message]) -> bytes:
        lengths = dict(zip(cls.ordered_fieldnames, cls.array_lengths, strict=True))
        values = [self._value(name, ftype, lengths[name], cls.msgname)
                  for name, ftype in zip(cls.fieldnames, cls.fieldtypes, strict=True)]
        message = cls(*values)
        data = message.pack(self.mav)
        self.mav.seq = (self.mav.seq + 1) & 0xFF
        return bytes(data)

    def _driving_command(self) -> bytes:
        rng = self.rng
        nan = math.nan
        target = rng.choice(self.systems)
        lat = LAT0 + rng.randint(-3000, 3000)
        lon = LON0 + rng.randint(-3000, 3000)
        command, params = rng.choice([
            (MavCmd.COMPONENT_ARM_DISARM, (1.0, 0.0)),
            (MavCmd.COMPONENT_ARM_DISARM, (0.0, 0.0)),
            (MavCmd.NAV_TAKEOFF, (nan,) * 7),
            (MavCmd.DO_SET_MODE, (1.0, 4.0, 3.0)),  # HOLD
            (MavCmd.DO_SET_MODE, (1.0, 4.0, 4.0)),  # MISSION
            (MavCmd.DO_SET_MODE, (1.0, 6.0, 0.0)),  # OFFBOARD
            (MavCmd.NAV_LAND, (nan,) * 7),
            (MavCmd.NAV_RETURN_TO_LAUNCH, ()),
            (MavCmd.MISSION_START, (0.0, 0.0)),
            (MavCmd.DO_REPOSITION, (-1.0, 1.0, 0.0, nan, lat * 1e-7, lon * 1e-7, nan)),
        ])
        p = [*params, *([0.0] * (7 - len(params)))]
        message = self.mav.command_long_encode(target, 1, command, 0, *p)
        data = message.pack(self.mav)
        self.mav.seq = (self.mav.seq + 1) & 0xFF
        return bytes(data)

    # --------------------------------------------------------------- mutations
    def frames(self, count: int) -> list[bytes]:
        """`count` frames, each valid or mutated."""
        rng = self.rng
        picked = rng.choices(self.corpus, k=count)
        kinds = rng.choices(self._kinds, cum_weights=self._cumulative, k=count)
        self.counts.update(kinds)
        return [data if kind == "valid" else self._mutate(data, kind)
                for data, kind in zip(picked, kinds, strict=True)]

    def _mutate(self, data: bytes, kind: str) -> bytes:
        rng = self.rng
        if len(data) < HEADER_V2 + 3:
            return data
        if kind == "scrambled":  # absurd payload bytes, checksum valid again
            payload = bytearray(data[HEADER_V2:-2])
            for _ in range(rng.randint(1, 4)):
                payload[rng.randrange(len(payload))] = rng.getrandbits(8)
            return _with_crc(data[:HEADER_V2] + bytes(payload))
        if kind == "truncated":
            return data[:rng.randrange(1, len(data))]
        if kind == "bad_crc":
            return data[:-2] + bytes([data[-2] ^ (1 + rng.getrandbits(7)), data[-1]])
        if kind == "bad_length":
            return data[:1] + bytes([rng.getrandbits(8)]) + data[2:]
        if kind == "unknown_id":
            msg_id = rng.choice(UNKNOWN_IDS)
            return data[:7] + msg_id.to_bytes(3, "little") + data[10:]
        if kind == "bit_flips":
            flipped = bytearray(data)
            for _ in range(rng.randint(1, 6)):
                bit = rng.randrange(len(flipped) * 8)
                flipped[bit // 8] ^= 1 << (bit % 8)
            return bytes(flipped)
        if kind == "spliced":  # bytes inserted or deleted somewhere
            at = rng.randrange(len(data))
            if rng.random() < 0.5:
                return data[:at] + rng.randbytes(rng.randint(1, 5)) + data[at:]
            return data[:at] + data[at + rng.randint(1, 5):]
        if kind == "resized":  # another payload length, checksum valid
            payload = data[HEADER_V2:-2]
            size = rng.randint(0, 255)
            payload = payload[:size] + rng.randbytes(max(0, size - len(payload)))
            return _with_crc(data[:1] + bytes([size]) + data[2:HEADER_V2] + payload)
        if kind == "other_type":  # another handled message id, checksum valid
            msg_id = self._classes[rng.choice(self._names)].id
            return _with_crc(data[:7] + msg_id.to_bytes(3, "little") + data[10:-2])
        if kind == "header_flags":  # signed, unknown incompatibility or compat flags
            flagged = _with_crc(data[:2] + bytes([rng.choice([0x01, 0x02, 0x80, 0xFF]),
                                                  rng.getrandbits(8)]) + data[4:-2])
            return flagged + rng.randbytes(13) if rng.random() < 0.5 else flagged
        return rng.randbytes(rng.randint(1, 40))  # junk

    def datagram(self, frames: int) -> bytes:
        return b"".join(self.frames(frames))

    def mixed_datagram(self) -> tuple[bytes, int]:
        """One datagram of 1 to 8 frames, some of them twice, now and then with junk between
        them; and its number of parts."""
        rng = self.rng
        r = rng.random()
        count = 1 if r < 0.35 else 2 if r < 0.55 else rng.randint(3, 8)
        parts: list[bytes] = []
        for frame in self.frames(count):
            parts.extend([frame, frame] if rng.random() < 0.1 else [frame])
        if rng.random() < 0.05:
            parts.insert(rng.randrange(len(parts) + 1), rng.randbytes(rng.randint(1, 40)))
        return b"".join(parts), len(parts)


def _with_crc(frame_without_crc: bytes) -> bytes:
    msg_id = int.from_bytes(frame_without_crc[7:10], "little")
    crc = mavlink.x25crc(frame_without_crc[1:])
    crc.accumulate(bytes([mavlink.mavlink_map[msg_id].crc_extra]))
    return frame_without_crc + crc.crc.to_bytes(2, "little")
