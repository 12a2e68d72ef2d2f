"""The parameter protocol as QGroundControl and MAVSDK drive it, over real UDP with pymavlink."""

from __future__ import annotations

import asyncio
import math
import struct

import pytest

from emulator.flight.params import PARAM_DEFINITIONS
from emulator.geo import DEFAULT_ORIGIN
from tests.mavlink_client import MavClient, running_swarm

REAL32, INT32 = 9, 6
N_PARAMS = len(PARAM_DEFINITIONS)
NAMES = [d.name for d in PARAM_DEFINITIONS]


def bytewise(value: int) -> float:
    """PX4's PARAM_ENCODE_BYTEWISE: the int32's bytes carried in the float field."""
    return struct.unpack("<f", struct.pack("<i", value))[0]


def unbytewise(value: float) -> int:
    return struct.unpack("<i", struct.pack("<f", value))[0]


def f32(value: float) -> float:
    return struct.unpack("<f", struct.pack("<f", value))[0]


def wire_value(m) -> float:
    return float(unbytewise(m.param_value)) if m.param_type == INT32 else m.param_value


async def fetch_all_params(client: MavClient, system: int, *, quiet_s: float = 0.3,
                           rounds: int = 5) -> tuple[dict[int, object], list[int]]:
    """QGroundControl's algorithm: REQUEST_LIST, collect until quiet, then re-request each
    missing index with PARAM_REQUEST_READ. Returns ({index: PARAM_VALUE}, re-requested)."""
    client.send(client.mav.param_request_list_encode(system, 1))
    start = client.mark
    await client.wait_for("PARAM_VALUE", system=system, timeout=2.0)
    seen = -1
    while True:  # wait for the stream to go quiet
        await asyncio.sleep(quiet_s)
        now = len(client.messages("PARAM_VALUE", system=system, since=start))
        if now == seen:
            break
        seen = now
    got: dict[int, object] = {}
    count = None
    for m in client.messages("PARAM_VALUE", system=system, since=start):
        got.setdefault(m.param_index, m)
        count = m.param_count
    assert count is not None
    rerequested: list[int] = []
    for _ in range(rounds):
        missing = [i for i in range(count) if i not in got]
        if not missing:
            break
        for i in missing:
            rerequested.append(i)
            m = await client.param_read(system, index=i)
            got[m.param_index] = m
    return got, rerequested


async def test_request_list_sends_every_parameter_exactly_once() -> None:
    async with running_swarm(2) as (swarm, client):
        client.send(client.mav.param_request_list_encode(1, 1))
        start = client.mark
        await client.wait_for("PARAM_VALUE", system=1)
        await asyncio.sleep(0.5)
        values = client.messages("PARAM_VALUE", system=1, since=start)
        assert len(values) == N_PARAMS
        assert sorted(m.param_index for m in values) == list(range(N_PARAMS))
        assert {m.param_count for m in values} == {N_PARAMS}
        assert [m.param_id for m in sorted(values, key=lambda m: m.param_index)] == NAMES
        params = swarm.fleet.autopilots[0].params
        for m in values:
            assert m.get_srcComponent() == 1
            expected = params[m.param_id]
            if PARAM_DEFINITIONS[m.param_index].is_int:
                assert m.param_type == INT32
                assert unbytewise(m.param_value) == int(expected)
            else:
                assert m.param_type == REAL32
                assert m.param_value == pytest.approx(expected, rel=1e-6)
        # the list went to vehicle 1 only: vehicle 2 sent no parameters
        assert not client.messages("PARAM_VALUE", system=2, since=start)
        # MAV_SYS_ID tells the vehicles apart
        sys_id = next(m for m in values if m.param_id == "MAV_SYS_ID")
        assert unbytewise(sys_id.param_value) == 1


async def test_missing_parameters_are_recovered_by_index() -> None:
    lost = {0, 7, 23, N_PARAMS - 1}
    async with running_swarm(1) as (swarm, client):
        dropped: list[int] = []

        def drop_first_copy(m) -> bool:
            if m.get_type() == "PARAM_VALUE" and m.param_index in lost and \
                    m.param_index not in dropped:
                dropped.append(m.param_index)
                return True
            return False

        client.drop = drop_first_copy
        got, rerequested = await fetch_all_params(client, 1)
        assert sorted(dropped) == sorted(lost)
        assert sorted(rerequested) == sorted(lost)
        assert sorted(got) == list(range(N_PARAMS))
        for i, m in got.items():
            assert m.param_id == NAMES[i]
            assert wire_value(m) == pytest.approx(swarm.fleet.autopilots[0].params[NAMES[i]],
                                                  rel=1e-6)


async def test_request_read_by_name_and_by_index() -> None:
    async with running_swarm(2) as (swarm, client):
        ap2 = swarm.fleet.autopilots[1]
        m = await client.param_read(2, "MPC_XY_VEL_MAX")
        assert (m.param_id, m.param_type, m.param_count) == ("MPC_XY_VEL_MAX", REAL32, N_PARAMS)
        assert m.param_index == NAMES.index("MPC_XY_VEL_MAX")
        assert m.param_value == pytest.approx(ap2.params["MPC_XY_VEL_MAX"])
        assert m.get_srcSystem() == 2

        index = NAMES.index("BAT_N_CELLS")
        m = await client.param_read(2, index=index)
        assert (m.param_id, m.param_type, m.param_index) == ("BAT_N_CELLS", INT32, index)
        assert unbytewise(m.param_value) == 4

        # index wins over name when it is >= 0 (MAVLink spec)
        m = await client.param_read(2, "MPC_XY_VEL_MAX", index=0)
        assert m.param_id == NAMES[0]
        # MAVSDK's get_takeoff_altitude: by name, index -1
        m = await client.param_read(2, "MIS_TAKEOFF_ALT", index=-1)
        assert m.param_value == pytest.approx(10.0)


async def test_request_read_of_unknown_name_or_index_answers_statustext_only() -> None:
    async with running_swarm(1) as (_swarm, client):
        client.send(client.mav.param_request_read_encode(1, 1, b"NO_SUCH_PARAM", -1))
        text = await client.wait_for("STATUSTEXT", system=1)
        assert "NO_SUCH_PARAM" in text.text
        await client.expect_none("PARAM_VALUE", system=1, within=0.4)

        client.send(client.mav.param_request_read_encode(1, 1, b"", N_PARAMS + 5))
        text = await client.wait_for("STATUSTEXT", system=1)
        assert str(N_PARAMS + 5) in text.text
        await client.expect_none("PARAM_VALUE", system=1, within=0.4)


async def _cruise_ground_speed(client: MavClient, system: int, north_m: float) -> float:
    """Fly north by `north_m` with DO_REPOSITION (no speed given) and return the highest
    horizontal speed GLOBAL_POSITION_INT reported on the way."""
    ack = await client.command_long(system, 400, 1.0)
    assert ack.result == 0
    ack = await client.command_long(system, 22, math.nan, 0, 0, math.nan, math.nan,
                                    math.nan, math.nan)
    assert ack.result == 0
    await client.wait_for("EXTENDED_SYS_STATE", system=system,
                          where=lambda m: m.landed_state == 2, timeout=5.0)
    lat, lon, alt = DEFAULT_ORIGIN.to_geodetic(5.0 * (system - 1), north_m, 10.0)
    ack = await client.command_int(system, 192, frame=0, p2=1, x=round(lat * 1e7),
                                   y=round(lon * 1e7), z=alt)
    assert ack.result == 0
    start = client.mark
    await client.wait_for("GLOBAL_POSITION_INT", system=system, timeout=15.0,
                          where=lambda m: abs(m.lat - round(lat * 1e7)) < 20
                          and math.hypot(m.vx, m.vy) < 20)
    speeds = [math.hypot(m.vx, m.vy) / 100.0
              for m in client.messages("GLOBAL_POSITION_INT", system=system, since=start)]
    return max(speeds)


@pytest.mark.slow
async def test_param_set_real32_echoes_and_changes_the_flight() -> None:
    async with running_swarm(2, speed=10.0) as (swarm, client):
        ap1, ap2 = swarm.fleet.autopilots[:2]
        echo = await client.param_set(1, "MPC_XY_CRUISE", 4.0, REAL32)
        assert (echo.param_id, echo.param_type) == ("MPC_XY_CRUISE", REAL32)
        assert echo.param_value == pytest.approx(4.0)
        assert echo.param_index == NAMES.index("MPC_XY_CRUISE")
        assert echo.param_count == N_PARAMS
        assert ap1.params["MPC_XY_CRUISE"] == pytest.approx(4.0)
        assert swarm.fleet.dyn.speed_xy_m_s[0] == pytest.approx(4.0)
        assert ap2.params["MPC_XY_CRUISE"] == pytest.approx(8.0)  # per vehicle
        # a read-back gives the new value
        assert (await client.param_read(1, "MPC_XY_CRUISE")).param_value == pytest.approx(4.0)

        slow, fast = await asyncio.gather(_cruise_ground_speed(client, 1, 80.0),
                                          _cruise_ground_speed(client, 2, 80.0))
        assert 3.5 <= slow <= 4.3, slow
        assert 7.0 <= fast <= 8.5, fast


@pytest.mark.slow
async def test_param_set_int32_uses_px4_bytewise_encoding() -> None:
    async with running_swarm(1) as (swarm, client):
        ap = swarm.fleet.autopilots[0]
        before = await client.wait_for("SYS_STATUS", system=1, timeout=2.0)
        echo = await client.param_set(1, "BAT_N_CELLS", bytewise(6), INT32)
        assert echo.param_type == INT32
        assert unbytewise(echo.param_value) == 6
        assert ap.params["BAT_N_CELLS"] == 6
        after = await client.wait_for("SYS_STATUS", system=1, timeout=2.0)
        # the battery voltage follows the cell count
        assert after.voltage_battery / before.voltage_battery == pytest.approx(6 / 4, rel=0.02)

        # A large id whose bytes would be a NaN/denormal as a float still round-trips.
        big = 0x7FC0_0001
        echo = await client.param_set(1, "CAL_ACC0_ID", bytewise(big), INT32)
        assert unbytewise(echo.param_value) == big
        assert ap.params["CAL_ACC0_ID"] == big


async def test_out_of_range_values_are_echoed_unchanged_with_a_statustext() -> None:
    async with running_swarm(1) as (swarm, client):
        ap = swarm.fleet.autopilots[0]
        cases = [
            ("MPC_XY_CRUISE", 100.0, REAL32, 8.0),
            ("MPC_XY_CRUISE", math.nan, REAL32, 8.0),
            ("MPC_XY_CRUISE", math.inf, REAL32, 8.0),
            ("MPC_XY_CRUISE", -1.0, REAL32, 8.0),
            ("BAT_N_CELLS", bytewise(99), INT32, 4),
            ("BAT_N_CELLS", bytewise(-3), INT32, 4),
            ("MAV_SYS_ID", bytewise(0), INT32, 1),
        ]
        for name, value, ptype, kept in cases:
            echo = await client.param_set(1, name, value, ptype)
            assert echo.param_id == name
            assert wire_value(echo) == pytest.approx(kept), (name, value)
            assert ap.params[name] == pytest.approx(kept)
            text = await client.wait_for("STATUSTEXT", system=1)
            assert name in text.text, text.text
        assert swarm.fleet.dyn.speed_xy_m_s[0] == pytest.approx(8.0)


async def test_param_set_of_unknown_name_gets_statustext_and_no_value() -> None:
    async with running_swarm(1) as (_swarm, client):
        client.send(client.mav.param_set_encode(1, 1, b"NOT_A_PARAM", 3.0, REAL32))
        text = await client.wait_for("STATUSTEXT", system=1)
        assert "NOT_A_PARAM" in text.text
        await client.expect_none("PARAM_VALUE", within=0.5)


async def test_param_set_for_another_system_is_ignored() -> None:
    async with running_swarm(2) as (swarm, client):
        echo = await client.param_set(2, "MPC_XY_CRUISE", 6.0)
        assert echo.get_srcSystem() == 2
        assert swarm.fleet.autopilots[0].params["MPC_XY_CRUISE"] == pytest.approx(8.0)
        assert swarm.fleet.autopilots[1].params["MPC_XY_CRUISE"] == pytest.approx(6.0)
        assert not client.messages("PARAM_VALUE", system=1, since=client.mark)
        assert f32(echo.param_value) == pytest.approx(6.0)
