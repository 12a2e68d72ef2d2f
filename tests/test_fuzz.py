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
tests the swarm, not the luck of the dice. The fuzzer is the suite's seeded frame fuzzer
(tests/frame_fuzz.py): the frames are the same on every run.
"""

from __future__ import annotations

import asyncio
import socket
import time

import pytest

from emulator.geo import DEFAULT_ORIGIN
from emulator.mavlink.codec import DatagramDecoder
from tests.flight_check import recover_and_fly
from tests.frame_fuzz import READ_ONLY, FrameFuzzer
from tests.mavlink_client import (
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
        fuzzer = FrameFuzzer(SEED, systems=FUZZED_SYSTEMS)
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
                        data, n = fuzzer.mixed_datagram()
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
