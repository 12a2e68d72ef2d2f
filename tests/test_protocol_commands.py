"""The command protocol (COMMAND_LONG / COMMAND_INT -> COMMAND_ACK) over real UDP."""

from __future__ import annotations

import asyncio
import itertools
import math
import statistics

import pytest

from emulator.flight.modes import FlightMode
from emulator.geo import DEFAULT_ORIGIN
from tests.mavlink_client import GCS_COMPONENT, GCS_SYSTEM, MavClient, running_swarm

ACCEPTED, TEMPORARILY_REJECTED, DENIED, UNSUPPORTED, FAILED = 0, 1, 2, 3, 4
NAN = math.nan
CMD_ARM, CMD_TAKEOFF, CMD_SET_MODE, CMD_REPOSITION = 400, 22, 176, 192
CMD_SET_INTERVAL, CMD_REQUEST_MESSAGE = 511, 512


async def arm_and_take_off(client: MavClient, system: int) -> None:
    assert (await client.command_long(system, CMD_ARM, 1.0)).result == ACCEPTED
    ack = await client.command_long(system, CMD_TAKEOFF, NAN, NAN, NAN, NAN, NAN, NAN, NAN)
    assert ack.result == ACCEPTED
    await client.wait_for("EXTENDED_SYS_STATE", system=system,
                          where=lambda m: m.landed_state == 2, timeout=6.0)


async def expect_denied(client: MavClient, system: int, command: int, *params: float,
                        text: str) -> None:
    ack = await client.command_long(system, command, *params)
    assert ack.result == DENIED, ack.to_dict()
    status = await client.wait_for("STATUSTEXT", system=system)
    assert text.lower() in status.text.lower(), status.text


def state(swarm, k: int) -> tuple:
    ap = swarm.fleet.autopilots[k]
    dyn = swarm.fleet.dyn
    return (ap.armed, ap.in_air, ap.mode, ap.home_m, tuple(dyn.goal_m[k]),
            int(dyn.control[k]))


async def test_unknown_command_is_unsupported() -> None:
    async with running_swarm(2) as (swarm, client):
        before = state(swarm, 0)
        ack = await client.command_long(1, 31999, 1, 2, 3, 4, 5, 6, 7)
        assert (ack.result, ack.command) == (UNSUPPORTED, 31999)
        assert (ack.target_system, ack.target_component) == (GCS_SYSTEM, GCS_COMPONENT)
        assert ack.get_srcSystem() == 1 and ack.get_srcComponent() == 1
        ack = await client.command_int(2, 31998)
        assert (ack.result, ack.command, ack.get_srcSystem()) == (UNSUPPORTED, 31998, 2)
        # MAV_CMD_DO_FLIGHTTERMINATION is real MAVLink but not implemented
        ack = await client.command_long(1, 185, 1.0)
        assert ack.result == UNSUPPORTED
        assert state(swarm, 0) == before
        # the broadcast PING from MAVSDK is not answered; a PING to the vehicle is
        client.send(client.mav.ping_encode(123, 7, 0, 0))
        await client.expect_none("PING", within=0.3)
        client.send(client.mav.ping_encode(456, 8, 1, 1))
        pong = await client.wait_for("PING", system=1)
        assert (pong.time_usec, pong.seq, pong.target_system) == (456, 8, GCS_SYSTEM)


async def test_invalid_parameters_are_denied_with_a_statustext_and_change_nothing() -> None:
    async with running_swarm(2) as (swarm, client):
        ap = swarm.fleet.autopilots[0]
        before = state(swarm, 0)
        await expect_denied(client, 1, CMD_ARM, 7.0, text="param1")
        await expect_denied(client, 1, CMD_ARM, NAN, text="param1")
        await expect_denied(client, 1, CMD_ARM, math.inf, text="param1")
        await expect_denied(client, 1, CMD_SET_MODE, 1, 99, 0, text="unknown PX4 mode")
        await expect_denied(client, 1, CMD_SET_MODE, 1, 4, 7, text="unknown PX4 mode")
        await expect_denied(client, 1, CMD_SET_MODE, 1, NAN, NAN, text="number")
        await expect_denied(client, 1, CMD_SET_MODE, math.inf, 4, 3, text="number")
        await expect_denied(client, 1, CMD_SET_MODE, 0, 4, 3, text="custom")
        assert state(swarm, 0) == before
        assert not swarm.recorder.events("d1", kinds=("arm", "mode"))

        # takeoff above the 120 m ceiling, and an infinite altitude, while armed
        assert (await client.command_long(1, CMD_ARM, 1.0)).result == ACCEPTED
        assert ap.armed
        home_amsl = DEFAULT_ORIGIN.altitude_amsl_m
        before = state(swarm, 0)
        await expect_denied(client, 1, CMD_TAKEOFF, NAN, NAN, NAN, NAN, NAN, NAN,
                            home_amsl + 500.0, text="ceiling")
        await expect_denied(client, 1, CMD_TAKEOFF, NAN, NAN, NAN, NAN, NAN, NAN,
                            math.inf, text="infinite")
        await expect_denied(client, 1, CMD_TAKEOFF, NAN, NAN, NAN, NAN, NAN, NAN,
                            home_amsl - 5.0, text="below home")
        assert state(swarm, 0) == before
        assert not ap.in_air
        assert not swarm.recorder.events("d1", kinds=("takeoff",))

        # DO_REPOSITION to latitude 95 while flying: denied, the goal stays where it was
        await arm_and_take_off(client, 2)
        await asyncio.sleep(0.3)
        before = state(swarm, 1)
        await expect_denied(client, 2, CMD_REPOSITION, -1, 1, 0, NAN, 95.0, 8.5, home_amsl + 20,
                            text="latitude")
        await expect_denied(client, 2, CMD_REPOSITION, -1, 1, 0, NAN, 47.4, 200.0,
                            home_amsl + 20, text="latitude")
        ack = await client.command_int(2, CMD_REPOSITION, frame=0, p2=1, x=950_000_000,
                                       y=85_000_000, z=home_amsl + 20)
        assert ack.result == DENIED
        ack = await client.command_int(2, CMD_REPOSITION, frame=0, p2=1, x=474_000_000,
                                       y=85_455_940, z=math.inf)
        assert ack.result == DENIED
        lat, lon, _ = DEFAULT_ORIGIN.to_geodetic(5.0, 30.0, 0.0)
        ack = await client.command_int(2, CMD_REPOSITION, frame=0, p2=1, x=round(lat * 1e7),
                                       y=round(lon * 1e7), z=home_amsl + 1000.0)
        assert ack.result == DENIED  # above the ceiling
        ack = await client.command_int(2, CMD_REPOSITION, frame=3, p1=1000.0, p2=1,
                                       x=round(lat * 1e7), y=round(lon * 1e7), z=20.0)
        assert ack.result == DENIED  # faster than MPC_XY_VEL_MAX
        assert state(swarm, 1) == before


@pytest.mark.slow
async def test_command_int_reposition_flies_there() -> None:
    async with running_swarm(2, speed=10.0) as (swarm, client):
        await arm_and_take_off(client, 1)
        # MAVSDK goto_location: HOLD first, then COMMAND_INT 192, frame 0, z AMSL, p4 yaw rad
        assert (await client.command_long(1, CMD_SET_MODE, 1, 4, 3)).result == ACCEPTED
        lat, lon, alt = DEFAULT_ORIGIN.to_geodetic(30.0, 40.0, 15.0)
        ack = await client.command_int(1, CMD_REPOSITION, frame=0, p1=NAN, p2=1, p3=NAN,
                                       p4=math.radians(90.0), x=round(lat * 1e7),
                                       y=round(lon * 1e7), z=alt)
        assert ack.result == ACCEPTED
        ap = swarm.fleet.autopilots[0]
        target_lat, target_lon = round(lat * 1e7), round(lon * 1e7)
        m = await client.wait_for(
            "GLOBAL_POSITION_INT", system=1, timeout=15.0,
            where=lambda m: abs(m.lat - target_lat) < 30 and abs(m.lon - target_lon) < 40
            and abs(m.relative_alt - 15000) < 500 and math.hypot(m.vx, m.vy) < 30,
        )
        assert m.alt == pytest.approx(alt * 1000, abs=500)
        x, y, z = ap.position_m
        assert (x, y, z) == pytest.approx((30.0, 40.0, 15.0), abs=2.5)
        assert ap.mode is FlightMode.HOLD
        heading = await client.wait_for("GLOBAL_POSITION_INT", system=1, timeout=5.0,
                                        where=lambda m: abs(m.hdg - 9000) < 300)
        assert heading.hdg == pytest.approx(9000, abs=300)
        # relative-altitude frame (6, GLOBAL_RELATIVE_ALT_INT) also works
        ack = await client.command_int(1, CMD_REPOSITION, frame=6, p2=1, x=target_lat,
                                       y=target_lon, z=25.0)
        assert ack.result == ACCEPTED
        await client.wait_for("GLOBAL_POSITION_INT", system=1, timeout=10.0,
                              where=lambda m: abs(m.relative_alt - 25000) < 500)
        # vehicle 2 never moved
        assert swarm.fleet.autopilots[1].position_m == pytest.approx((5.0, 0.0, 0.0))


async def test_request_message_answers_after_the_ack() -> None:
    async with running_swarm(2) as (_swarm, client):
        # silence the periodic HOME_POSITION so the one-shot reply is unmistakable
        assert (await client.command_long(1, CMD_SET_INTERVAL, 242, -1)).result == ACCEPTED
        await asyncio.sleep(0.2)
        for msg_id, name in ((148, "AUTOPILOT_VERSION"), (242, "HOME_POSITION")):
            client.send(client.mav.command_long_encode(1, 1, CMD_REQUEST_MESSAGE, 0, msg_id,
                                                       0, 0, 0, 0, 0, 0))
            start = client.mark
            ack_at = await client.wait_index("COMMAND_ACK", system=1,
                                             where=lambda m: m.command == CMD_REQUEST_MESSAGE)
            assert client.received[ack_at].msg.result == ACCEPTED
            reply_at = await client.wait_index(name, system=1, since=start)
            assert reply_at > ack_at, f"{name} arrived before its COMMAND_ACK"
            await asyncio.sleep(0.3)
            assert len(client.messages(name, system=1, since=start)) == 1
        version = client.messages("AUTOPILOT_VERSION", system=1)[-1]
        assert version.capabilities & 16  # MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE
        assert version.capabilities & 4 and version.capabilities & 8192  # MISSION_INT, MAVLINK2
        home = client.messages("HOME_POSITION", system=1)[-1]
        lat, lon, alt = DEFAULT_ORIGIN.to_geodetic(0.0, 0.0, 0.0)
        assert (home.latitude, home.longitude) == (round(lat * 1e7), round(lon * 1e7))
        assert home.altitude == round(alt * 1000)
        # vehicle 2 only answered what it was asked: nothing
        assert not client.messages("AUTOPILOT_VERSION", system=2)

        # legacy MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES and MAV_CMD_GET_HOME_POSITION
        ack = await client.command_long(2, 520, 1)
        assert ack.result == ACCEPTED
        await client.wait_for("AUTOPILOT_VERSION", system=2)
        ack = await client.command_long(2, 410)
        assert ack.result == ACCEPTED
        await client.wait_for("HOME_POSITION", system=2)
        # a message that cannot be requested is denied and nothing is sent
        ack = await client.command_long(1, CMD_REQUEST_MESSAGE, 9999)
        assert ack.result == DENIED
        ack = await client.command_long(1, CMD_REQUEST_MESSAGE, NAN)
        assert ack.result == DENIED


def rate_hz(client: MavClient, name: str, system: int, since: int) -> float:
    """The stream's rate from the median gap between arrivals: a stream is paced in wall time,
    and a test process starved of CPU for a moment (a loaded machine) sends the few messages
    it missed late or not at all, which stretches one gap but leaves the others as scheduled."""
    stamps = [r.t for r in client.timed(name, system=system, since=since)]
    if len(stamps) < 3:
        return 0.0
    return 1.0 / statistics.median(b - a for a, b in itertools.pairwise(stamps))


@pytest.mark.slow
async def test_set_message_interval_changes_the_measured_rate() -> None:
    async with running_swarm(2) as (_swarm, client):
        start = len(client.received)
        await asyncio.sleep(1.2)
        assert rate_hz(client, "ATTITUDE", 1, start) == pytest.approx(10.0, rel=0.2)

        ack = await client.command_long(1, CMD_SET_INTERVAL, 30, 40_000)  # 25 Hz
        assert ack.result == ACCEPTED
        ack = await client.command_long(1, CMD_SET_INTERVAL, 33, 500_000)  # 2 Hz
        assert ack.result == ACCEPTED
        ack = await client.command_long(1, CMD_SET_INTERVAL, 245, 1e6)  # MAVSDK's request
        assert ack.result == ACCEPTED
        start = len(client.received)
        await asyncio.sleep(2.0)
        assert rate_hz(client, "ATTITUDE", 1, start) == pytest.approx(25.0, rel=0.2)
        assert rate_hz(client, "GLOBAL_POSITION_INT", 1, start) == pytest.approx(2.0, rel=0.25)
        assert rate_hz(client, "ATTITUDE", 2, start) == pytest.approx(10.0, rel=0.2)
        assert 1 <= len(client.timed("EXTENDED_SYS_STATE", system=1, since=start)) <= 3

        # -1 stops a stream, 0 restores its default rate
        ack = await client.command_long(1, CMD_SET_INTERVAL, 30, -1)
        assert ack.result == ACCEPTED
        await asyncio.sleep(0.15)
        await client.expect_none("ATTITUDE", system=1, within=0.6, since=len(client.received))
        ack = await client.command_long(1, CMD_SET_INTERVAL, 30, 0)
        assert ack.result == ACCEPTED
        start = len(client.received)
        await asyncio.sleep(1.2)
        assert rate_hz(client, "ATTITUDE", 1, start) == pytest.approx(10.0, rel=0.2)

        # the heartbeat cannot be switched off; bad intervals are denied
        assert (await client.command_long(1, CMD_SET_INTERVAL, 0, -1)).result == DENIED
        assert (await client.command_long(1, CMD_SET_INTERVAL, 30, -5)).result == DENIED
        assert (await client.command_long(1, CMD_SET_INTERVAL, NAN, 1000)).result == DENIED
        assert (await client.command_long(1, CMD_SET_INTERVAL, 9999, 1000)).result == DENIED


async def test_arm_hold_and_mode_changes_show_in_the_heartbeat() -> None:
    # real time: at 10x the 10 s pre-flight auto-disarm would beat the 1 Hz heartbeat
    async with running_swarm(1, speed=1.0) as (swarm, client):
        # MAVSDK sends DO_SET_MODE Hold before arming, with stale flags in p1
        assert (await client.command_long(1, CMD_SET_MODE, 1, 4, 3)).result == ACCEPTED
        assert (await client.command_long(1, CMD_ARM, 1.0, NAN)).result == ACCEPTED
        hb = await client.wait_for("HEARTBEAT", system=1, component=1, timeout=2.0,
                                   where=lambda m: m.base_mode & 128)
        assert hb.base_mode & 1  # CUSTOM_MODE_ENABLED
        assert hb.custom_mode == FlightMode.HOLD.custom_mode
        assert swarm.fleet.autopilots[0].armed
        assert (await client.command_long(1, CMD_ARM, 0.0)).result == ACCEPTED
        await client.wait_for("HEARTBEAT", system=1, component=1, timeout=2.0,
                              where=lambda m: not m.base_mode & 128)
        assert [e.kind for e in swarm.recorder.events("d1", kinds=("arm", "disarm"))] == [
            "arm", "disarm"]


async def test_set_home_with_an_absurd_altitude_is_denied_and_the_swarm_survives() -> None:
    """DO_SET_HOME 1e9 m up used to be accepted; the next HOME_POSITION or
    GLOBAL_POSITION_INT then overflowed its int32 millimetres and killed the swarm (the
    reply closed the socket; the stream killed the scheduler)."""
    async with running_swarm(2) as (swarm, client):
        ap = swarm.fleet.autopilots[0]
        lat, lon, _ = DEFAULT_ORIGIN.to_geodetic(20.0, 10.0, 0.0)
        for altitude in (1e9, -1e9, 3e38):
            await expect_denied(client, 1, 179, 0, NAN, NAN, NAN, lat, lon, altitude,
                                text="Set home")
            ack = await client.command_int(1, 179, frame=0, p1=0, x=round(lat * 1e7),
                                           y=round(lon * 1e7), z=altitude)
            assert ack.result == DENIED
        assert ap.home_m == (0.0, 0.0, 0.0)
        # a sensible one is accepted and reported at once
        mark = len(client.received)
        ack = await client.command_long(1, 179, 0, NAN, NAN, NAN, lat, lon,
                                        DEFAULT_ORIGIN.altitude_amsl_m + 2.0)
        assert ack.result == ACCEPTED
        home = await client.wait_for("HOME_POSITION", system=1, since=mark)
        # (COMMAND_LONG carries degrees as float32: about 1e-6 deg of rounding)
        assert home.latitude == pytest.approx(lat * 1e7, abs=50)
        assert home.longitude == pytest.approx(lon * 1e7, abs=50)
        assert home.altitude == round((DEFAULT_ORIGIN.altitude_amsl_m + 2.0) * 1000)
        assert ap.home_m == pytest.approx((20.0, 10.0, 2.0), abs=0.5)
        gpi = await client.wait_for("GLOBAL_POSITION_INT", system=1, since=len(client.received))
        assert gpi.relative_alt == -2000
