"""Fuzzing the running swarm over real UDP, then flying a mission on it.

More than 100,000 frames are thrown at the swarm's socket: frames of every message type the
emulator handles, with random field values (NaN, infinities, huge and extreme integers,
garbage strings), then mutated at the byte level (flipped bits, truncation, duplication,
several frames per datagram, junk around them, length and message-id edits with the checksum
made valid again). The event loop must record no exception, the scheduler must stay alive,
and afterwards the swarm must still fly: a mission end to end on the protected vehicle, and
one waypoint on each fuzzed vehicle once a client has restored its parameters (in-range
values are configuration) and landed and disarmed it (tests/flight_check.py).

Vehicles 1 and 2 take the full storm (they arm, take off, fly, change parameters, run
offboard, upload missions...). Vehicle 3 is kept clean: every datagram is first decoded
with the emulator's own decoder, and one that would change vehicle 3 (addressed to it, or a
state-changing broadcast) is replaced by another, so that the mission flown on it afterwards
tests the swarm, not the luck of the dice. The fuzzer is a seeded ``random.Random``:
the frames are the same on every run.
"""

from __future__ import annotations

import asyncio
import math
import random
import socket
import struct
import time

import pytest
from pymavlink.generator.mavcrc import x25crc

from emulator.flight.params import PARAM_DEFINITIONS
from emulator.geo import DEFAULT_ORIGIN
from emulator.mavlink.codec import DatagramDecoder
from emulator.mavlink.commands import HANDLERS
from tests.flight_check import recover_and_fly
from tests.mavlink_client import (
    mavlink,
    running_swarm,
    scheduler_alive,
    send_datagram,
    swarm_socket_open,
)

pytestmark = pytest.mark.slow

SEED = 20240611
TARGET_FRAMES = 100_000
BATCH_DATAGRAMS = 24
PROTECTED_SYSTEM = 3
FUZZED_SYSTEMS = (1, 2)

# Message types the emulator handles (weights), plus some it ignores.
HANDLED = {
    "COMMAND_LONG": 18, "COMMAND_INT": 10, "PARAM_SET": 12, "PARAM_REQUEST_READ": 4,
    "PARAM_REQUEST_LIST": 0.4, "MISSION_COUNT": 5, "MISSION_ITEM_INT": 9, "MISSION_ITEM": 4,
    "MISSION_REQUEST_LIST": 2, "MISSION_REQUEST_INT": 3, "MISSION_REQUEST": 2,
    "MISSION_CLEAR_ALL": 1, "MISSION_SET_CURRENT": 3, "SET_POSITION_TARGET_LOCAL_NED": 8,
    "SET_POSITION_TARGET_GLOBAL_INT": 5, "PING": 2, "TIMESYNC": 1,
    "FILE_TRANSFER_PROTOCOL": 2, "REQUEST_DATA_STREAM": 1, "HEARTBEAT": 1, "MISSION_ACK": 1,
    "SET_MODE": 1,
}
# What may reach the protected vehicle as a broadcast: requests that change nothing.
READ_ONLY = frozenset({
    "PARAM_REQUEST_READ", "PARAM_REQUEST_LIST", "MISSION_REQUEST_LIST",
    "MISSION_REQUEST_INT", "MISSION_REQUEST", "PING", "REQUEST_DATA_STREAM",
    "FILE_TRANSFER_PROTOCOL", "MISSION_ACK",
})

CLASSES = {name: mavlink.mavlink_map[getattr(mavlink, f"MAVLINK_MSG_ID_{name}")]
           for name in HANDLED}
TYPE_NAMES = list(HANDLED)
TYPE_WEIGHTS = [HANDLED[n] for n in TYPE_NAMES]
# SIM_HOVER_ENDUR only sets how fast the battery drains: a legitimately short endurance
# empties it during the storm, and an empty battery refuses to arm by design. The faults'
# parameters and command (data-link loss, failure injection: a failed motor refuses to arm by
# design) are left out so the seeded storm stays the one it was; the storm of
# tests/test_hardening_mavlink.py covers them.
FAULT_PARAMS = ("COM_DL_LOSS_T", "NAV_DLL_ACT", "SYS_FAILURE_EN")
# The same for what PX4 conformance added later (offboard yaw rates, orbit, geofence):
# the storm of tests/test_hardening_mavlink.py covers them.
LATER_PARAMS = ("MC_YAWRATE_MAX", "MC_ORBIT_RAD_MAX", "MC_ORBIT_YAW_MOD", "GF_ACTION")
LATER_COMMANDS = (34, 241)  # MAV_CMD_DO_ORBIT, MAV_CMD_PREFLIGHT_CALIBRATION
PARAM_NAMES = [d.name.encode() for d in PARAM_DEFINITIONS
               if d.name != "SIM_HOVER_ENDUR" and d.name not in FAULT_PARAMS + LATER_PARAMS]
COMMANDS = [*sorted(c for c in HANDLERS if c != 420 and c not in LATER_COMMANDS),
            16, 17, 20, 21, 22, 176, 183, 185, 246, 31000]

F32_MAX = 3.4028234663852886e38
SPECIAL_FLOATS = [
    math.nan, math.inf, -math.inf, 0.0, -0.0, 1.0, -1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 0.5,
    -2.0, 10.0, 100.0, 1e6, -1e6, 1e30, -1e30, F32_MAX, -F32_MAX, 1.4e-45, 21196.0,
    2**31, -(2**31), 4294967295.0, 65535.0, 1e-3,
]
INT_RANGES = {
    "uint8_t": (0, 255), "int8_t": (-128, 127), "uint16_t": (0, 65535),
    "int16_t": (-32768, 32767), "uint32_t": (0, 2**32 - 1), "int32_t": (-(2**31), 2**31 - 1),
    "uint64_t": (0, 2**64 - 1), "int64_t": (-(2**63), 2**63 - 1),
}
LAT0, LON0 = round(DEFAULT_ORIGIN.latitude_deg * 1e7), round(DEFAULT_ORIGIN.longitude_deg * 1e7)
ALT0 = DEFAULT_ORIGIN.altitude_amsl_m


class Fuzzer:
    """Seeded generator of fuzz datagrams."""

    def __init__(self, seed: int) -> None:
        self.rng = random.Random(seed)
        self.mav = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
        self.mav.robust_parsing = True

    # ------------------------------------------------------------ field values
    def any_float(self) -> float:
        rng = self.rng
        r = rng.random()
        if r < 0.45:
            return rng.choice(SPECIAL_FLOATS)
        if r < 0.75:
            return rng.uniform(-200.0, 200.0)
        if r < 0.9:
            return rng.uniform(-1e9, 1e9)
        return struct.unpack("<f", rng.getrandbits(32).to_bytes(4, "little"))[0]

    def any_int(self, ftype: str) -> int:
        lo, hi = INT_RANGES[ftype]
        rng = self.rng
        r = rng.random()
        if r < 0.3:
            return rng.choice([lo, hi, 0, 1, min(hi, 2), max(lo, -1), min(hi, 255), hi // 2])
        if r < 0.6:
            return rng.randint(max(lo, -5), min(hi, 10))
        return rng.randint(lo, hi)

    def value(self, name: str, ftype: str, length: int, type_name: str) -> object:
        rng = self.rng
        if ftype == "char":
            if name == "param_id" and rng.random() < 0.75:
                return rng.choice(PARAM_NAMES)
            return bytes(rng.getrandbits(8) for _ in range(rng.randint(0, length)))
        if length:
            if ftype in INT_RANGES:
                return [self.any_int(ftype) for _ in range(length)]
            return [self.any_float() for _ in range(length)]
        if name == "target_system":
            r = rng.random()
            if r < 0.8:
                return rng.choice(FUZZED_SYSTEMS)
            if r < 0.9:
                return 0
            return rng.choice([4, 77, 200, 255, rng.randint(0, 255)])
        if name == "target_component":
            return rng.choice([0, 1, 1, 1, 100, 190, rng.randint(0, 255)])
        if name == "command":
            return rng.choice(COMMANDS) if rng.random() < 0.9 else rng.randint(0, 65535)
        if name in ("seq", "count") and rng.random() < 0.85:
            return rng.randint(0, 6)
        if name == "mission_type" and rng.random() < 0.8:
            return rng.choice([0, 0, 0, 1, 2, 255])
        if name in ("frame", "coordinate_frame") and rng.random() < 0.8:
            return rng.choice([0, 1, 2, 3, 5, 6, 7, 8, 9, 10, 11, 12])
        if name == "param_type" and rng.random() < 0.8:
            return rng.choice([6, 9, 9, 1, 2, 3, 4, 5, 10])
        if name == "type_mask" and rng.random() < 0.6:
            return rng.choice([0x9F8, 0xDC7, 0xDFF, 0, 0xFFFF, 0x7, 0x38])
        if name in ("x", "lat_int") and ftype == "int32_t" and rng.random() < 0.6:
            return LAT0 + rng.randint(-20_000, 20_000)
        if name in ("y", "lon_int") and ftype == "int32_t" and rng.random() < 0.6:
            return LON0 + rng.randint(-30_000, 30_000)
        if ftype in INT_RANGES:
            return self.any_int(ftype)
        # floats with a meaning: positions near the origin, sensible altitudes
        if type_name == "COMMAND_LONG" and name in ("param5", "param6") and rng.random() < 0.5:
            base = DEFAULT_ORIGIN.latitude_deg if name == "param5" else \
                DEFAULT_ORIGIN.longitude_deg
            return base + rng.uniform(-0.002, 0.002)
        if type_name == "MISSION_ITEM" and name in ("x", "y") and rng.random() < 0.6:
            base = DEFAULT_ORIGIN.latitude_deg if name == "x" else DEFAULT_ORIGIN.longitude_deg
            return base + rng.uniform(-0.002, 0.002)
        if name in ("z", "alt", "param7") and rng.random() < 0.5:
            return rng.choice([rng.uniform(0, 150), ALT0 + rng.uniform(-20, 150)])
        if name in ("x", "y", "z", "vx", "vy", "vz") and rng.random() < 0.5:
            return rng.uniform(-60.0, 60.0)
        return self.any_float()

    def message(self) -> mavlink.MAVLink_message:
        name = self.rng.choices(TYPE_NAMES, TYPE_WEIGHTS)[0]
        cls = CLASSES[name]
        lengths = dict(zip(cls.ordered_fieldnames, cls.array_lengths, strict=True))
        args = [self.value(f, t, lengths[f], name)
                for f, t in zip(cls.fieldnames, cls.fieldtypes, strict=True)]
        return cls(*args)

    def frame(self) -> bytes:
        msg = self.message()
        data = msg.pack(self.mav)
        self.mav.seq = (self.mav.seq + 1) & 0xFF
        return data

    # --------------------------------------------------------------- mutation
    def recrc(self, frame: bytearray) -> bytes:
        """Make a (header-edited) v2 frame's checksum valid again for its message id."""
        if len(frame) < 10 or frame[0] != 0xFD:
            return bytes(frame)
        msg_id = frame[7] | frame[8] << 8 | frame[9] << 16
        cls = mavlink.mavlink_map.get(msg_id)
        end = min(10 + frame[1], len(frame))
        crc = x25crc(bytes(frame[1:end]))
        if cls is not None:
            crc.accumulate(bytes([cls.crc_extra]))
        return bytes(frame[:end]) + crc.crc.to_bytes(2, "little")

    def mutate(self, frame: bytes) -> bytes:
        rng = self.rng
        b = bytearray(frame)
        kind = rng.randrange(9)
        if kind == 0:  # flip a few bits
            for _ in range(rng.randint(1, 6)):
                i = rng.randrange(len(b) * 8)
                b[i // 8] ^= 1 << (i % 8)
        elif kind == 1:  # truncate
            del b[rng.randrange(len(b)):]
        elif kind == 2:  # overwrite random bytes
            for _ in range(rng.randint(1, 4)):
                b[rng.randrange(len(b))] = rng.getrandbits(8)
        elif kind == 3:  # insert or delete bytes
            i = rng.randrange(len(b))
            if rng.random() < 0.5:
                b[i:i] = bytes(rng.getrandbits(8) for _ in range(rng.randint(1, 5)))
            else:
                del b[i:i + rng.randint(1, 5)]
        elif kind == 4:  # a different payload length, checksum valid
            new_len = rng.randint(0, 255)
            payload = b[10:10 + b[1]]
            payload = payload[:new_len] + bytes(rng.getrandbits(8)
                                                for _ in range(max(0, new_len - len(payload))))
            b = bytearray(b[:10]) + payload
            b[1] = len(payload)
            return self.recrc(b)
        elif kind == 5:  # another message id of a handled type, checksum valid
            cls = CLASSES[rng.choice(TYPE_NAMES)]
            b[7:10] = cls.id.to_bytes(3, "little")
            return self.recrc(b)
        elif kind == 6:  # random payload bytes, checksum valid
            for i in range(10, 10 + b[1]):
                if rng.random() < 0.3:
                    b[i] = rng.getrandbits(8)
            return self.recrc(b)
        elif kind == 7:  # header flags: signed / unknown incompatibility / compat bits
            b[2] = rng.choice([0x01, 0x02, 0x80, 0xFF])
            b[3] = rng.getrandbits(8)
            if rng.random() < 0.5:
                return self.recrc(b) + bytes(rng.getrandbits(8) for _ in range(13))
            return self.recrc(b)
        else:  # pure garbage of similar size
            return bytes(rng.getrandbits(8) for _ in range(len(b)))
        return bytes(b)

    def datagram(self) -> tuple[bytes, int]:
        """One datagram and the number of frames in it."""
        rng = self.rng
        r = rng.random()
        if r < 0.35:
            n = 1
        elif r < 0.55:
            n = 2
        else:
            n = rng.randint(3, 8)
        parts = []
        for _ in range(n):
            frame = self.frame()
            p = rng.random()
            if p < 0.45:
                parts.append(frame)
            elif p < 0.55:
                parts.extend([frame, frame])  # duplicated
            else:
                parts.append(self.mutate(frame))
        if rng.random() < 0.05:
            parts.insert(rng.randrange(len(parts) + 1),
                         bytes(rng.getrandbits(8) for _ in range(rng.randint(1, 40))))
        return b"".join(parts), len(parts)


def touches_protected(messages) -> bool:
    for m in messages:
        target = getattr(m, "target_system", None)
        if target == PROTECTED_SYSTEM:
            return True
        if target == 0 and m.get_type() not in READ_ONLY:
            return True
    return False


async def fly_mission(client, swarm, system: int) -> None:
    """Upload a 4-item mission, arm, start it; wait for every item to be reached."""
    k = system - 1
    x0, y0, _ = swarm.fleet.autopilots[k].position_m
    points = [(x0, y0 + 30.0, 12.0), (x0 + 25.0, y0 + 30.0, 15.0)]
    items = [client.mission_item(system, 0, 22, 0.0, 0.0, 10.0)]
    for x, y, z in points:
        lat, lon, _ = DEFAULT_ORIGIN.to_geodetic(x, y, 0.0)
        items.append(client.mission_item(system, len(items), 16, lat, lon, z))
    items.append(client.mission_item(system, len(items), 21, 0.0, 0.0, 0.0))
    ack = await client.upload_mission(system, items)
    assert ack.type == 0, ack.to_dict()
    downloaded = await client.download_mission(system)
    assert [(m.command, m.x, m.y) for m in downloaded] == [(m.command, m.x, m.y) for m in items]
    start = len(client.received)
    assert (await client.command_long(system, 400, 1.0)).result == 0
    assert (await client.command_long(system, 176, 1, 4, 4)).result == 0
    await client.wait_for("MISSION_ITEM_REACHED", system=system, since=start, timeout=20.0,
                          where=lambda m: m.seq == len(items) - 1)
    reached = [m.seq for m in client.messages("MISSION_ITEM_REACHED", system=system,
                                              since=start)]
    assert reached == list(range(len(items)))
    vid = f"d{system}"
    truth = [e.data["item"] for e in swarm.recorder.events(vid, kinds=("mission_item_reached",))]
    assert truth == list(range(len(items)))
    assert swarm.recorder.events(vid, kinds=("mission_complete",))
    landed = swarm.recorder.events(vid, kinds=("landed",))
    assert landed[-1].data["position_m"][:2] == pytest.approx(list(points[-1][:2]), abs=2.5)


async def test_fuzzed_swarm_survives_and_flies_a_mission() -> None:
    wall_start = time.monotonic()
    async with running_swarm(3, speed=10.0) as (swarm, client):
        endpoint = swarm.endpoints[0]
        protected = swarm.fleet.autopilots[PROTECTED_SYSTEM - 1]
        params_before = dict(protected.params)
        params_at_start = {s: dict(swarm.fleet.autopilots[s - 1].params) for s in FUZZED_SYSTEMS}
        fuzzer = Fuzzer(SEED)
        mirror = DatagramDecoder()  # the emulator's own decoder, to predict what it sees
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.setblocking(False)
        sock.bind(("127.0.0.1", 0))
        client.paused = True  # the storm's replies reach every peer; do not parse them
        stats0 = swarm.stats()
        steps0 = swarm.fleet.step_count
        frames = datagrams = replaced = 0
        fuzz_start = time.monotonic()
        try:
            while frames < TARGET_FRAMES:
                for _ in range(BATCH_DATAGRAMS):
                    while True:
                        data, n = fuzzer.datagram()
                        counts = mirror.frames_ok, mirror.frames_bad
                        if not touches_protected(mirror.decode(data)):
                            break
                        mirror.frames_ok, mirror.frames_bad = counts  # not sent after all
                        replaced += 1
                    await send_datagram(sock, data, endpoint.local_address)
                    frames += n
                    datagrams += 1
                # let the swarm drain its socket (UDP would drop what overflows it)
                deadline = time.monotonic() + 5.0
                while endpoint.stats.datagrams_in - stats0.datagrams_in < datagrams:
                    assert time.monotonic() < deadline, "the swarm stopped reading its socket"
                    await asyncio.sleep(0)
                errors = client.loop_errors
                assert errors is not None and not errors.errors, errors and errors.describe()
                assert scheduler_alive(swarm), "the scheduler task died during the fuzz"
                assert swarm_socket_open(swarm), "the swarm's socket was closed during the fuzz"
                assert swarm.stats().internal_errors == 0, "a handler raised during the fuzz"
        finally:
            sock.close()
        fuzz_wall = time.monotonic() - fuzz_start
        await asyncio.sleep(1.0)  # still paused: discard the replies the storm provoked
        client.paused = False
        assert client.loop_errors is not None and not client.loop_errors.errors
        stats = swarm.stats()

        # every datagram was read, and decoded exactly as the mirror decoder predicted
        assert stats.datagrams_in - stats0.datagrams_in == datagrams
        assert stats.frames_ok - stats0.frames_ok == mirror.frames_ok
        assert stats.frames_bad - stats0.frames_bad == mirror.frames_bad
        assert mirror.frames_ok > 30_000 and mirror.frames_bad > 20_000
        assert frames >= TARGET_FRAMES
        # the physics kept running during the storm (at least a quarter of real time x10)
        assert (swarm.fleet.step_count - steps0) * swarm.fleet.dt_s > fuzz_wall * 10.0 / 4
        # the fuzzed vehicles really were driven around
        kinds = {e.kind for e in swarm.recorder.events("d1")} | \
            {e.kind for e in swarm.recorder.events("d2")}
        assert {"arm", "takeoff", "mode"} <= kinds, kinds
        # the protected vehicle was not touched
        assert not swarm.recorder.events(f"d{PROTECTED_SYSTEM}")
        assert dict(protected.params) == params_before

        # the fuzzed vehicles still answer (the client first works through the storm's replies)
        for system in FUZZED_SYSTEMS:
            m = await client.param_read(system, "MPC_XY_VEL_MAX", timeout=10.0)
            assert m.param_id == "MPC_XY_VEL_MAX"
            ack = await client.command_long(system, 31999, timeout=10.0)
            assert ack.result == 3
        for system in (1, 2, 3):
            await client.wait_for("HEARTBEAT", system=system, timeout=3.0,
                                  since=len(client.received))

        # ... and the swarm flies: a mission on the protected vehicle, and once restored, a
        # waypoint on each fuzzed one
        await asyncio.gather(
            fly_mission(client, swarm, PROTECTED_SYSTEM),
            *(recover_and_fly(client, swarm, system, params_at_start[system])
              for system in FUZZED_SYSTEMS),
        )
        print(f"fuzz: {frames} frames in {datagrams} datagrams ({replaced} replaced), "
              f"ok {mirror.frames_ok}, bad {mirror.frames_bad}, {fuzz_wall:.1f} s; "
              f"total {time.monotonic() - wall_start:.1f} s")
