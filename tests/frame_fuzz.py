"""A seeded generator of hostile MAVLink datagrams, cheap enough for millions of frames.

A corpus of valid frames is encoded once with pymavlink: every message type a vehicle handles
(and a few it ignores), with random field values that are often absurd (NaN, infinities,
extreme integers, garbage strings, unknown commands, frames and masks). Each frame drawn from
it is then sent as it is or mutated at the byte level: its payload scrambled with the
checksum made valid again (a valid frame carrying absurd values), truncated, its checksum
broken, its length byte changed, its message id changed to one nobody knows, or replaced by
junk. Several frames go in one datagram. The same seed gives the same datagrams.

State-changing traffic that would make a vehicle unfit to fly afterwards by design (failure
injection and its parameters, the simulated battery endurance) is left out, as in
tests/test_fuzz.py: the storm must not break a vehicle, and a vehicle told to fail is not
broken.
"""

from __future__ import annotations

import itertools
import math
import random
import struct
from collections import Counter

from pymavlink.dialects.v20 import common as mavlink

from emulator.flight.params import PARAM_DEFINITIONS
from emulator.geo import DEFAULT_ORIGIN
from emulator.mavlink.commands import HANDLERS
from mavlink_vocabulary import MavCmd

__all__ = ["FAULT_PARAMS", "MUTATIONS", "FrameFuzzer"]

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
FAULT_PARAMS = ("COM_DL_LOSS_T", "NAV_DLL_ACT", "SYS_FAILURE_EN", "SIM_HOVER_ENDUR")
PARAM_NAMES = [d.name.encode() for d in PARAM_DEFINITIONS if d.name not in FAULT_PARAMS]
COMMANDS = [*sorted(c for c in HANDLERS if c != MavCmd.INJECT_FAILURE),
            MavCmd.NAV_WAYPOINT, MavCmd.NAV_LOITER_UNLIM, 183, 185, 246, 31000]
F32_MAX = 3.4028234663852886e38
SPECIAL_FLOATS = [
    math.nan, math.inf, -math.inf, 0.0, -0.0, 1.0, -1.0, 2.0, 3.0, 4.0, 6.0, 0.5, 10.0, 100.0,
    1e6, -1e6, 1e30, -1e30, F32_MAX, -F32_MAX, 1.4e-45, 21196.0, 2**31, 4294967295.0, 65535.0,
]
INT_RANGES = {
    "uint8_t": (0, 255), "int8_t": (-128, 127), "uint16_t": (0, 65535),
    "int16_t": (-32768, 32767), "uint32_t": (0, 2**32 - 1), "int32_t": (-(2**31), 2**31 - 1),
    "uint64_t": (0, 2**64 - 1), "int64_t": (-(2**63), 2**63 - 1),
}
LAT0 = round(DEFAULT_ORIGIN.latitude_deg * 1e7)
LON0 = round(DEFAULT_ORIGIN.longitude_deg * 1e7)
# (mutation, weight): what happens to a frame drawn from the corpus
MUTATIONS = (("valid", 40), ("scrambled", 15), ("truncated", 10), ("bad_crc", 10),
             ("bad_length", 10), ("unknown_id", 10), ("junk", 5))
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
        classes = {name: mavlink.mavlink_map[getattr(mavlink, f"MAVLINK_MSG_ID_{name}")]
                   for name in TYPES}
        names = list(TYPES)
        weights = [TYPES[n] for n in names]
        self.corpus = [self._frame(classes[name])
                       for name in self.rng.choices(names, weights, k=CORPUS_SIZE)]
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
            return rng.choice([lo, hi, 0, 1, min(hi, 2), max(lo, -1), hi // 2])
        if r < 0.6:
            return rng.randint(max(lo, -5), min(hi, 10))
        return rng.randint(lo, hi)

    def _value(self, name: str, ftype: str, length: int) -> object:
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
        return self._float()

    def _frame(self, cls: type[mavlink.MAVLink_message]) -> bytes:
        lengths = dict(zip(cls.ordered_fieldnames, cls.array_lengths, strict=True))
        values = [self._value(name, ftype, lengths[name])
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
        return rng.randbytes(rng.randint(1, 40))  # junk

    def datagram(self, frames: int) -> bytes:
        return b"".join(self.frames(frames))


def _with_crc(frame_without_crc: bytes) -> bytes:
    msg_id = int.from_bytes(frame_without_crc[7:10], "little")
    crc = mavlink.x25crc(frame_without_crc[1:])
    crc.accumulate(bytes([mavlink.mavlink_map[msg_id].crc_extra]))
    return frame_without_crc + crc.crc.to_bytes(2, "little")
