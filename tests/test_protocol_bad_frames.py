"""Malformed input over real UDP: the swarm drops it, counts it, and keeps flying."""

from __future__ import annotations

import asyncio
import math
import random

import pytest
from pymavlink.dialects.v10 import common as mavlink1
from pymavlink.generator.mavcrc import x25crc

from emulator.geo import DEFAULT_ORIGIN
from tests.mavlink_client import MavClient, running_swarm

NAN = math.nan
COMMAND_LONG_CRC_EXTRA = 152


def recrc(frame: bytes, crc_extra: int) -> bytes:
    """A v2 frame (header possibly edited) with its checksum made valid again."""
    b = bytearray(frame)
    end = 10 + b[1]
    crc = x25crc(bytes(b[1:end]))
    crc.accumulate(bytes([crc_extra]))
    b[end:end + 2] = crc.crc.to_bytes(2, "little")
    return bytes(b[:end + 2])


def arm_frame(client: MavClient, system: int) -> bytes:
    return client.pack(client.mav.command_long_encode(system, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0))


class Counters:
    def __init__(self, swarm) -> None:
        self.swarm = swarm
        self.endpoint = swarm.endpoints[0]
        self.reset()

    def reset(self) -> None:
        s = self.swarm.stats()
        self.ok, self.bad, self.unroutable = (s.frames_ok, s.frames_bad,
                                              self.endpoint.stats.unroutable)
        self.datagrams = s.datagrams_in

    def delta(self) -> tuple[int, int, int]:
        s = self.swarm.stats()
        return (s.frames_ok - self.ok, s.frames_bad - self.bad,
                self.endpoint.stats.unroutable - self.unroutable)

    async def send(self, client: MavClient, datagrams: list[bytes]) -> None:
        """Send, pacing so the swarm's socket buffer never overflows (UDP would drop)."""
        for i, data in enumerate(datagrams):
            client.send_raw(data)
            if i % 8 == 7:
                await self.settle(i + 1)
        await self.settle(len(datagrams))

    async def settle(self, datagrams: int) -> None:
        """Wait until the swarm has read `datagrams` more datagrams."""
        for _ in range(400):
            if self.swarm.stats().datagrams_in - self.datagrams >= datagrams:
                return
            await asyncio.sleep(0.005)
        raise AssertionError("the swarm did not read the datagrams sent to it")


async def fly_away(client: MavClient, system: int, north_m: float) -> None:
    assert (await client.command_long(system, 400, 1.0)).result == 0
    assert (await client.command_long(system, 22, NAN, NAN, NAN, NAN, NAN, NAN, NAN)).result == 0
    await client.wait_for("EXTENDED_SYS_STATE", system=system,
                          where=lambda m: m.landed_state == 2, timeout=6.0)
    lat, lon, alt = DEFAULT_ORIGIN.to_geodetic(5.0 * (system - 1), north_m, 20.0)
    ack = await client.command_int(system, 192, frame=0, p2=1, x=round(lat * 1e7),
                                   y=round(lon * 1e7), z=alt)
    assert ack.result == 0


@pytest.mark.slow
async def test_bad_frames_are_dropped_and_counted_while_the_swarm_flies_on() -> None:
    rng = random.Random(1234)
    async with running_swarm(3, speed=10.0) as (swarm, client):
        await fly_away(client, 2, 250.0)
        ap1, ap2, ap3 = swarm.fleet.autopilots
        counters = Counters(swarm)
        start = len(client.received)
        north_before = ap2.position_m[1]

        # 1. garbage datagrams (no frame start in them at all), an empty one, a jumbo one
        garbage = [bytes(rng.choice(range(0, 0xFD)) for _ in range(rng.randint(1, 300)))
                   for _ in range(100)]
        await counters.send(client, [*garbage, b"",
                                     bytes(rng.getrandbits(8) for _ in range(60_000))])
        ok, bad, _ = counters.delta()
        assert ok == 0
        assert bad >= 100 + 1

        # 2. truncated frames: an ARM for vehicle 1 cut short, at every possible length
        counters.reset()
        full = arm_frame(client, 1)
        await counters.send(client, [full[:cut] for cut in range(1, len(full))])
        assert counters.delta() == (0, len(full) - 1, 0)

        # 3. CRC-broken frames: one flipped bit anywhere in an ARM for vehicle 1
        counters.reset()
        flipped = []
        for bit in range(8, 8 * len(full)):  # (bits 0-7: the start marker, see garbage)
            b = bytearray(arm_frame(client, 1))
            b[bit // 8] ^= 1 << (bit % 8)
            flipped.append(bytes(b))
        await counters.send(client, flipped)
        sent = len(flipped)
        ok, bad, _ = counters.delta()
        assert ok == 0
        assert bad >= sent

        # 4. well-formed frames that must still be dropped: an unknown message id and an
        #    unknown incompatibility flag
        counters.reset()
        unknown_id = bytearray(arm_frame(client, 1))
        unknown_id[7:10] = (0x99, 0x99, 0x00)
        client.send_raw(recrc(bytes(unknown_id), 0))
        strange_flag = bytearray(arm_frame(client, 1))
        strange_flag[2] = 0x02
        client.send_raw(recrc(bytes(strange_flag), COMMAND_LONG_CRC_EXTRA))
        await counters.settle(2)
        assert counters.delta() == (0, 2, 0)

        # none of that armed vehicle 1 or drew a reply
        await asyncio.sleep(0.2)
        assert not ap1.armed and not ap3.armed
        assert not client.messages("COMMAND_ACK", since=start)
        assert not swarm.recorder.events("d1", kinds=("arm",))

        # 5. messages for systems that do not exist: valid, routed nowhere, unanswered
        counters.reset()
        for system in (4, 42, 200, 250):
            client.send(client.mav.command_long_encode(system, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0))
            client.send(client.mav.param_request_list_encode(system, 1))
        await counters.settle(8)
        assert counters.delta() == (8, 0, 8)
        await client.expect_none(("COMMAND_ACK", "PARAM_VALUE"), within=0.3, since=start)

        # 6. several valid frames (and junk between them) in one datagram all count
        counters.reset()
        packed = b"junk" + b"".join(
            client.pack(client.mav.param_request_read_encode(s, 1, b"", 0)) for s in (1, 2, 3)
        ) + b"\xfd\x09"
        mark = len(client.received)
        client.send_raw(packed)
        await counters.settle(1)
        ok, bad, _ = counters.delta()
        assert ok == 3 and bad == 2
        for s in (1, 2, 3):
            await client.wait_for("PARAM_VALUE", system=s, since=mark)

        # vehicle 2 kept flying throughout, and everyone still streams and answers
        assert ap2.position_m[1] > north_before + 5.0
        await client.wait_for("GLOBAL_POSITION_INT", system=2, timeout=15.0,
                              where=lambda m: m.relative_alt > 19_000
                              and abs(m.lat - round(DEFAULT_ORIGIN.to_geodetic(5, 250, 0)[0]
                                                    * 1e7)) < 30)
        for s in (1, 3):
            await client.wait_for("HEARTBEAT", system=s, since=len(client.received),
                                  timeout=2.0)
        ack = await client.command_long(1, 400, 1.0)
        assert ack.result == 0 and ap1.armed


async def test_mavlink1_frames_are_understood_like_px4() -> None:
    """PX4 accepts MAVLink 1 frames from a ground station (and answers in MAVLink 2)."""
    async with running_swarm(2) as (swarm, client):
        mav1 = mavlink1.MAVLink(None, srcSystem=255, srcComponent=190)
        frame = mav1.command_long_encode(2, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0).pack(mav1)
        assert frame[0] == 0xFE
        counters = Counters(swarm)
        mark = len(client.received)
        client.send_raw(frame)
        ack = await client.wait_for("COMMAND_ACK", system=2, since=mark)
        assert ack.result == 0
        assert swarm.fleet.autopilots[1].armed
        assert counters.delta()[:2] == (1, 0)
        # a v1 frame with a broken checksum is dropped and counted
        broken = bytearray(mav1.command_long_encode(1, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0).pack(mav1))
        broken[-1] ^= 0xFF
        counters.reset()
        client.send_raw(bytes(broken))
        await counters.settle(1)
        assert counters.delta()[:2] == (0, 1)
        assert not swarm.fleet.autopilots[0].armed


@pytest.mark.parametrize("kind", ["datagram_per_frame", "burst"])
@pytest.mark.slow
async def test_a_flood_of_valid_requests_does_not_stop_the_flight(kind: str) -> None:
    async with running_swarm(2, speed=10.0) as (swarm, client):
        await fly_away(client, 1, 120.0)
        counters = Counters(swarm)
        frames = [client.pack(client.mav.param_request_read_encode(2, 1, b"MPC_XY_CRUISE", -1))
                  for _ in range(300)]
        if kind == "burst":
            frames = [b"".join(frames[i:i + 30]) for i in range(0, len(frames), 30)]
        await counters.send(client, frames)
        assert counters.delta()[:2] == (300, 0)
        replies = 0
        for _ in range(1000):  # every request is answered, however loaded the machine
            replies = len(client.messages("PARAM_VALUE", system=2, since=0))
            if replies >= 300:
                break
            await asyncio.sleep(0.01)
        assert replies == 300
        target = round(DEFAULT_ORIGIN.to_geodetic(0, 120, 0)[0] * 1e7)
        await client.wait_for("GLOBAL_POSITION_INT", system=1, since=0, timeout=15.0,
                              where=lambda m: abs(m.lat - target) < 30)

