"""Values a client can send that used to be accepted and leave a vehicle unable to fly.

Regression tests over real UDP, one per defect: a DO_CHANGE_SPEED of 1.4e-45 m/s (the
vehicle then neither climbed, moved nor landed), the same speed through DO_REPOSITION and a
mission item, a home 6,000 km from the session, and the other absurd values found in the
command, mission and offboard handlers. Each is DENIED (or refused in MISSION_ACK / ignored
for a set-point) with a STATUSTEXT naming the value and the allowed range, and changes
nothing.

The storm test at the end generalises them. Frames with valid checksums and absurd field
values (tests/mavlink_strategies.py) of every message type a vehicle handles and every
command id, addressed to every vehicle of a 3-vehicle swarm and to broadcast 0, are sent
over loopback UDP in bursts: an exhaustive sweep of every command parameter through every
absurd value first, then one valid mission upload per vehicle followed by AUTO.MISSION and
arm (so that the storm meets vehicles flying a mission whatever its own uploads drew), then
hypothesis examples, one burst each. Invariants:

* after every burst: no exception reached the event loop, `swarm.stats().internal_errors`
  is 0, the scheduler task and the socket are alive, the swarm read every datagram, and no
  speed, rate, acceleration or acceptance limit of any vehicle is below its floor (the
  range minimum of the parameter it comes from);
* after the storm: every frame was decoded, every vehicle still answers (PARAM_VALUE,
  COMMAND_ACK, HEARTBEAT), and EVERY vehicle, once its parameters are restored by PARAM_SET
  (in-range values are configuration) and it is landed and disarmed, arms, takes off, flies
  one waypoint and lands there, per the ground truth `swarm.recorder`.

Hypothesis draws in synchronous @given functions (derandomized or seeded, no database, the
whole project imported first, tests/hypothesis_draws.py: the same frames on every run,
whatever other test files the session collected) that collect their examples; the async
test sends them.
"""

from __future__ import annotations

import asyncio
import math
import socket

import pytest
from hypothesis import HealthCheck, Phase, given, seed, settings

from emulator.flight.dynamics import TRACK_SETTLE
from emulator.flight.fleet import Fleet
from emulator.flight.mission import Cmd, MissionItem
from emulator.flight.modes import FlightMode
from emulator.geo import DEFAULT_ORIGIN
from emulator.mavlink.commands import HANDLERS
from emulator.mavlink.vehicle_link import HANDLED_MESSAGES
from emulator.scenario import default_scenario
from tests.flight_check import (
    assert_alive,
    assert_no_limit_below_its_floor,
    fly_one_waypoint,
    recover_and_fly,
    wait_truth,
)
from tests.mavlink_client import MavClient, mavlink, running_swarm, send_datagram
from tests.mavlink_strategies import (
    BASELINES,
    SYSTEMS,
    TARGETS,
    plausible_missions,
    storms,
    sweep,
    value_sweep,
)

ACCEPTED, DENIED = 0, 2
MISSION_INVALID_PARAM2 = 7
NAN, INF = math.nan, math.inf
ALT0 = DEFAULT_ORIGIN.altitude_amsl_m


async def expect_denied(client: MavClient, system: int, command: int, *params: float,
                        text: str, use_int: bool = False) -> str:
    """Send a command (COMMAND_LONG, or COMMAND_INT with x/y from params 5/6 in degrees);
    it must be DENIED with a STATUSTEXT containing `text`. Returns the STATUSTEXT."""
    if use_int:
        p = [*params] + [NAN] * (7 - len(params))
        ack = await client.command_int(system, command, p1=p[0], p2=p[1], p3=p[2], p4=p[3],
                                       x=round(p[4] * 1e7), y=round(p[5] * 1e7), z=p[6])
    else:
        ack = await client.command_long(system, command, *params)
    assert ack.result == DENIED, (params, ack.to_dict())
    status = await client.wait_for("STATUSTEXT", system=system)
    assert text.lower() in status.text.lower(), status.text
    return status.text


async def arm_and_take_off(client: MavClient, swarm, system: int) -> None:
    ap = swarm.fleet.autopilots[system - 1]
    t0 = swarm.fleet.now_s
    # at 20x, PX4's pre-flight auto-disarm (10 s) is half a wall second: a loaded machine
    # could let it pass between ARM and TAKEOFF
    await client.param_set(system, "COM_DISARM_PRFLT", -1.0)
    assert (await client.command_long(system, 400, 1.0)).result == ACCEPTED
    assert (await client.command_long(system, 22, *[NAN] * 7)).result == ACCEPTED
    await wait_truth(swarm, lambda: bool(swarm.recorder.events(
        ap.vehicle_id, t0_s=t0, kinds=("takeoff_complete",))), 30.0, "take-off")


def limits(swarm, k: int) -> tuple:
    dyn, ap = swarm.fleet.dyn, swarm.fleet.autopilots[k]
    return (ap.speed_override_m_s, float(dyn.speed_xy_m_s[k]), float(dyn.climb_m_s[k]),
            float(dyn.descent_m_s[k]), float(dyn.yaw_rate_deg_s[k]))


# ------------------------------------------------------------------ speeds
@pytest.mark.slow
async def test_change_speed_outside_the_airframe_range_is_denied() -> None:
    """DO_CHANGE_SPEED 1.4e-45 m/s was accepted and kept: ARM and TAKEOFF were then
    accepted and the vehicle stayed on the ground for good."""
    async with running_swarm(1, speed=20.0) as (swarm, client):
        before = limits(swarm, 0)
        for kind, speed, text in (
            (1, 1.4e-45, "Speed: speed 1.4e-45 m/s not in [0.5, 12]"),
            (0, 0.49, "airspeed 0.49 m/s not in [0.5, 12]"), (1, 0.0, "0 m/s not in [0.5, 12]"),
            (1, -3.0, "-3 m/s"), (1, NAN, "nan m/s"), (1, INF, "inf m/s not in [0.5, 12]"),
            (1, 12.5, "12.5 m/s not in [0.5, 12]"),
            (2, 0.3, "climb 0.3 m/s not in [0.5, 3]"), (2, 3.5, "3.5 m/s not in [0.5, 3]"),
            (3, 1e-3, "descent 0.001 m/s not in [0.5, 1.5]"), (3, 1.6, "[0.5, 1.5]"),
            (4, 5.0, "unknown speed type 4"), (1.5, 5.0, "unknown speed type 1.5"),
        ):
            await expect_denied(client, 1, 178, kind, speed, -1.0, text=text)
        assert limits(swarm, 0) == before
        # the range follows the parameters in force: MPC_XY_VEL_MAX 20 allows 15 m/s
        await client.param_set(1, "MPC_XY_VEL_MAX", 20.0)
        assert (await client.command_long(1, 178, 1, 15.0, -1)).result == ACCEPTED
        assert swarm.fleet.autopilots[0].speed_override_m_s == 15.0
        # the floor itself is accepted, and a vehicle at it still climbs, flies and lands
        assert (await client.command_long(1, 178, 1, 0.5, -1)).result == ACCEPTED
        assert (await client.command_long(1, 178, 2, 0.5, -1)).result == ACCEPTED
        assert (await client.command_long(1, 178, 3, 0.5, -1)).result == ACCEPTED
        await fly_one_waypoint(client, swarm, 1)
        # -1 and -2 restore the configured speeds
        assert (await client.command_long(1, 178, 1, -1.0, -1)).result == ACCEPTED
        assert (await client.command_long(1, 178, 2, -2.0, -1)).result == ACCEPTED
        assert swarm.fleet.autopilots[0].speed_override_m_s is None


async def test_reposition_speed_below_the_floor_is_refused_not_used() -> None:
    async with running_swarm(1, speed=20.0) as (swarm, client):
        ap = swarm.fleet.autopilots[0]
        await arm_and_take_off(client, swarm, 1)
        lat, lon, _ = DEFAULT_ORIGIN.to_geodetic(10.0, 0.0, 0.0)
        goal = tuple(swarm.fleet.dyn.goal_m[0])
        for speed in (1e-30, 1.4e-45, 0.2, INF, 12.5):
            await expect_denied(client, 1, 192, speed, 1, NAN, NAN, lat, lon, ALT0 + 10.0,
                                text="Reposition: speed", use_int=True)
        await expect_denied(client, 1, 192, 1e-30, 1, NAN, NAN, lat, lon, ALT0 + 10.0,
                            text="speed 1e-30 m/s not in [0.5, 12]", use_int=True)
        assert tuple(swarm.fleet.dyn.goal_m[0]) == goal
        for unset in (NAN, 0.0, -1.0):  # the configured speed
            ack = await client.command_int(1, 192, p1=unset, x=round(lat * 1e7),
                                           y=round(lon * 1e7), z=ALT0 + 10.0)
            assert ack.result == ACCEPTED
        assert swarm.fleet.dyn.speed_xy_m_s[0] == ap.params["MPC_XY_CRUISE"]


async def test_mission_speed_items_are_checked_at_upload_and_when_flown() -> None:
    async with running_swarm(1, speed=20.0) as (swarm, client):
        ap = swarm.fleet.autopilots[0]

        def items(speed_m_s: float) -> list:
            lat, lon, _ = DEFAULT_ORIGIN.to_geodetic(12.0, 0.0, 0.0)
            return [client.mission_item(1, 0, Cmd.NAV_TAKEOFF, 0.0, 0.0, 8.0),
                    client.mission_item(1, 1, Cmd.DO_CHANGE_SPEED, frame=2, p1=1.0,
                                        p2=speed_m_s, p3=-1.0),
                    client.mission_item(1, 2, Cmd.NAV_WAYPOINT, lat, lon, 8.0),
                    client.mission_item(1, 3, Cmd.NAV_LAND)]

        for speed in (1.4e-45, 0.0, 0.3, 31.0):
            ack = await client.upload_mission(1, items(speed))
            assert ack.type == MISSION_INVALID_PARAM2, speed
            status = await client.wait_for("STATUSTEXT", system=1, since=len(client.received) - 3)
            assert f"Item 1: speed {speed:.3g} m/s not in [0.5, 12]" == status.text
        assert ap.mission.total == 0
        # valid at upload, out of range when flown (MPC_XY_VEL_MAX lowered): refused, skipped
        assert (await client.upload_mission(1, items(11.0))).type == ACCEPTED
        await client.param_set(1, "MPC_XY_VEL_MAX", 5.0)
        mark = len(client.received)
        assert (await client.command_long(1, 400, 1.0)).result == ACCEPTED
        assert (await client.command_long(1, 176, 1, 4, 4)).result == ACCEPTED
        status = await client.wait_for("STATUSTEXT", system=1, since=mark, timeout=5.0,
                                       where=lambda m: m.text.startswith("Speed"))
        assert status.text == "Speed: speed 11 m/s not in [0.5, 5]"
        await wait_truth(swarm, lambda: bool(swarm.recorder.events(
            "d1", kinds=("mission_complete",))), 60.0, "mission")
        assert ap.speed_override_m_s is None


def test_vertical_rates_do_not_follow_the_horizontal_speed_limit() -> None:
    """The speed along a vertical line was capped at the horizontal limit x 1e9, so a
    horizontal speed of 1.4e-45 m/s froze take-off and landing too (pure dynamics)."""
    fleet = Fleet(default_scenario(1))
    ap = fleet.autopilots[0]
    ap.arm()
    ap.takeoff(10.0)
    fleet.dyn.speed_xy_m_s[0] = 1.4e-45  # below any floor: only the dynamics is tested
    fleet.run(10 * 50)
    assert ap.position_m[2] == pytest.approx(10.0, abs=0.1)
    ap.fly_to((0.0, 0.0, 4.0), tracking=TRACK_SETTLE)
    fleet.dyn.speed_xy_m_s[0] = 1.4e-45
    fleet.run(10 * 50)
    assert ap.position_m[2] == pytest.approx(4.0, abs=0.1)


# -------------------------------------------------------------------- home
async def test_set_home_far_from_the_session_is_denied_and_the_limit_is_a_parameter() -> None:
    async with running_swarm(1, speed=20.0) as (swarm, client):
        ap = swarm.fleet.autopilots[0]
        far = (DEFAULT_ORIGIN.latitude_deg - 54.0, DEFAULT_ORIGIN.longitude_deg)  # 6,000 km
        for use_int in (False, True):
            await expect_denied(client, 1, 179, 0, NAN, NAN, NAN, *far, ALT0, use_int=use_int,
                                text="Set home: 6e+06 m from origin, limit 10000 m")
        # configurable: SIM_HOME_MAXDIST 100 m refuses 150 m, accepts 50 m
        echo = await client.param_set(1, "SIM_HOME_MAXDIST", 100.0)
        assert echo.param_value == 100.0
        lat150, lon150, _ = DEFAULT_ORIGIN.to_geodetic(150.0, 0.0, 0.0)
        lat50, lon50, _ = DEFAULT_ORIGIN.to_geodetic(50.0, 0.0, 0.0)
        for use_int in (False, True):
            await expect_denied(client, 1, 179, 0, NAN, NAN, NAN, lat150, lon150, ALT0,
                                use_int=use_int, text="150 m from origin, limit 100 m")
        assert ap.home_m == (0.0, 0.0, 0.0)
        ack = await client.command_int(1, 179, p1=0, x=round(lat50 * 1e7), y=round(lon50 * 1e7),
                                       z=ALT0)
        assert ack.result == ACCEPTED
        assert ap.home_m == pytest.approx((50.0, 0.0, 0.0), abs=0.05)
        # out of range values are rejected, the limit stays
        echo = await client.param_set(1, "SIM_HOME_MAXDIST", 1e9)
        assert echo.param_value == 100.0
        # below the ground (take-off was then refused), above the ceiling, and so far from the
        # vehicle that every destination on its side would be outside the geofence
        lat0, lon0, _ = DEFAULT_ORIGIN.to_geodetic(0.0, 0.0, 0.0)
        await expect_denied(client, 1, 179, 0, NAN, NAN, NAN, lat0, lon0, ALT0 - 50.0,
                            text="Set home: altitude -50 m not in [0, 120] m")
        await expect_denied(client, 1, 179, 0, NAN, NAN, NAN, lat0, lon0, ALT0 + 500.0,
                            text="altitude 500 m not in [0, 120] m")
        await client.param_set(1, "GF_MAX_HOR_DIST", 40.0)
        await expect_denied(client, 1, 179, 0, NAN, NAN, NAN, lat50, lon50, ALT0,
                            text="Set home: 50 m from vehicle, fence 40 m")
        await client.param_set(1, "GF_MAX_HOR_DIST", 10000.0)
        # param1 = 1: the current position, on the ground and in the air
        assert (await client.command_long(1, 179, 1.0)).result == ACCEPTED
        assert ap.home_m == (0.0, 0.0, 0.0)
        await fly_one_waypoint(client, swarm, 1)
        await arm_and_take_off(client, swarm, 1)
        x, y, _ = ap.position_m
        assert (await client.command_long(1, 179, 1.0)).result == ACCEPTED
        assert ap.home_m == pytest.approx((x, y, 0.0), abs=0.05)


# ------------------------------------------------------------------ others
async def test_land_yaw_interval_and_offboard_absurd_values_are_refused() -> None:
    async with running_swarm(1, speed=20.0) as (swarm, client):
        ap = swarm.fleet.autopilots[0]
        await expect_denied(client, 1, 511, -1, 1e6, text="message id -1")
        await arm_and_take_off(client, swarm, 1)
        goal = tuple(swarm.fleet.dyn.goal_m[0])
        lat, lon, _ = DEFAULT_ORIGIN.to_geodetic(0.0, 50_000.0, 0.0)
        await expect_denied(client, 1, 21, NAN, NAN, NAN, NAN, lat, lon, NAN,
                            text="Land refused: 50000 m from home")
        await expect_denied(client, 1, 115, 90.0, 1.4e-45, 1, 0,
                            text="Yaw: yaw rate 1.4e-45 deg/s below 5")
        assert tuple(swarm.fleet.dyn.goal_m[0]) == goal and ap.mode is FlightMode.HOLD
        assert not swarm.fleet.dyn.yaw_tracking[0]
        # an offboard position set-point 50 km north is ignored with a STATUSTEXT
        client.send(client.mav.set_position_target_local_ned_encode(
            0, 1, 1, 1, 0x9F8, 50_000.0, 0.0, -10.0, 0, 0, 0, 0, 0, 0, 0.0, 0))
        status = await client.wait_for("STATUSTEXT", system=1)
        assert status.text.startswith("Offboard set-point refused: 50000 m from home")
        ack = await client.command_long(1, 176, 1, 6, 0)
        assert ack.result == DENIED  # no valid set-point: no OFFBOARD
        # velocity set-points fly until the ceiling (lowered to 15 m), then the vehicle holds
        await client.param_set(1, "GF_MAX_VER_DIST", 15.0)
        client.send(client.mav.set_position_target_local_ned_encode(
            0, 1, 1, 1, 0xDC7, 0, 0, 0, 0.0, 0.0, -3.0, 0, 0, 0, 0.0, 0))
        assert (await client.command_long(1, 176, 1, 6, 0)).result == ACCEPTED
        await wait_truth(swarm, lambda: bool(swarm.recorder.events(
            "d1", kinds=("failsafe",))), 20.0, "geofence hold")
        assert swarm.recorder.events("d1", kinds=("failsafe",))[-1].data["reason"] == "geofence"
        assert ap.mode is FlightMode.HOLD
        await wait_truth(swarm, lambda: swarm.fleet.dyn.speed_m_s(0) < 0.05, 10.0, "hold")
        assert 15.0 <= ap.position_m[2] <= 17.0


def test_a_paused_mission_hold_does_not_outlive_the_mission() -> None:
    """A waypoint hold of 3e38 s kept its timer (and the vehicle busy) after the mission was
    left; a timer that fired later would have run the next item of another mission."""
    fleet = Fleet(default_scenario(1))
    ap = fleet.autopilots[0]
    origin = fleet.world.origin
    lat, lon, _ = origin.to_geodetic(5.0, 0.0, 0.0)
    ap.mission.replace([
        MissionItem(0, 6, Cmd.NAV_TAKEOFF, z=5.0),
        MissionItem(1, 6, Cmd.NAV_WAYPOINT, param1=3e38, x=round(lat * 1e7),
                    y=round(lon * 1e7), z=5.0),
        MissionItem(2, 6, Cmd.NAV_LAND),
    ])
    ap.mission.enter_mission_mode()
    ap.arm()
    fleet.run(30 * 50)
    assert ap.mission.current == 1 and math.isfinite(fleet.timer_s[0]) and fleet.busy[0]
    ap.hold()
    assert fleet.timer_s[0] == math.inf
    assert fleet.run(30 * 50) < 30 * 50 and not fleet.busy[0]  # it comes to rest


# ------------------------------------------------------------------- storm
# Hypothesis examples, one burst each: the exhaustive value sweep and the sweeps already send
# every command and message type to every address; the storm adds their combinations and
# episodes, for which hypothesis's default count of examples is enough.
STORM_EXAMPLES = 100
SWEEP_EXAMPLES = 2  # the first of each is hypothesis's simplest (NaN and zeros)
STORM_SPEED = 25.0
_DETERMINISTIC = settings(derandomize=True, database=None, deadline=None,
                          suppress_health_check=list(HealthCheck),
                          phases=(Phase.explicit, Phase.generate))


def _collect_sweeps(sink: list[list]) -> None:
    """SWEEP_EXAMPLES sweeps per address and command message (fixed seeds)."""
    for i, (target, kind) in enumerate((t, k) for t in TARGETS
                                       for k in ("COMMAND_LONG", "COMMAND_INT")):
        @seed(i)
        @settings(_DETERMINISTIC, max_examples=SWEEP_EXAMPLES)
        @given(burst=sweep(target, kind))
        def collect(burst: list) -> None:
            sink.append(burst)

        collect()


@settings(_DETERMINISTIC, max_examples=STORM_EXAMPLES)
@given(burst=storms(max_parts=30))
def _collect_storm(sink: list[list], burst: list) -> None:
    sink.append(burst)


@pytest.mark.slow
async def test_storm_of_absurd_frames_leaves_every_vehicle_able_to_fly() -> None:
    assert set(BASELINES) == set(HANDLERS)
    values = value_sweep()
    bursts: list[list] = [values[i:i + 100] for i in range(0, len(values), 100)]
    bursts.append(plausible_missions())  # a mission flown, whatever the storm's uploads drew
    _collect_sweeps(bursts)  # the same frames whatever else the session collected
    _collect_storm(bursts)  # (tests/hypothesis_draws.py)
    sent = [m for burst in bursts for m in burst]
    # the storm covers every handled message type, every command, every address
    assert {m.get_type() for m in sent} >= HANDLED_MESSAGES
    commands = {(m.get_type(), m.command) for m in sent if m.get_type().startswith("COMMAND")}
    for kind in ("COMMAND_LONG", "COMMAND_INT"):
        assert {(kind, c) for c in HANDLERS} <= commands, kind
    assert set(TARGETS) <= {getattr(m, "target_system", None) for m in sent}

    async with running_swarm(3, speed=STORM_SPEED) as (swarm, client):
        params_at_start = [dict(ap.params) for ap in swarm.fleet.autopilots]
        endpoint = swarm.endpoints[0]
        mav = mavlink.MAVLink(None, srcSystem=254, srcComponent=190)
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.setblocking(False)
        sock.bind(("127.0.0.1", 0))
        client.paused = True  # the storm's replies reach every peer: do not parse them
        stats0 = swarm.stats()
        frames = 0
        try:
            for burst in bursts:
                for m in burst:
                    data = m.pack(mav)
                    mav.seq = (mav.seq + 1) & 0xFF
                    await send_datagram(sock, data, endpoint.local_address)
                    frames += 1
                deadline = asyncio.get_running_loop().time() + 5.0
                while endpoint.stats.datagrams_in - stats0.datagrams_in < frames:
                    assert asyncio.get_running_loop().time() < deadline, "socket not read"
                    await asyncio.sleep(0)
                assert_alive(swarm, client)
                assert_no_limit_below_its_floor(swarm)
                await asyncio.sleep(0.002)  # let the vehicles fly a little between bursts
        finally:
            sock.close()
        await asyncio.sleep(0.5)  # still paused: let the replies to the storm go by
        client.paused = False
        stats = swarm.stats()
        assert stats.frames_ok - stats0.frames_ok == frames == len(sent)
        assert stats.frames_bad == stats0.frames_bad
        # the storm reached deep state
        kinds = {e.kind for e in swarm.recorder.events()}
        assert {"arm", "takeoff", "mode", "home", "mission_start"} <= kinds, kinds
        assert_no_limit_below_its_floor(swarm)
        # every vehicle still answers
        for system in SYSTEMS:
            m = await client.param_read(system, "MPC_XY_CRUISE", timeout=5.0)
            assert m.param_id == "MPC_XY_CRUISE"
            assert (await client.command_long(system, 31999, timeout=5.0)).result == 3
            await client.wait_for("HEARTBEAT", system=system, timeout=3.0)
        # ... and flies
        await asyncio.gather(*(recover_and_fly(client, swarm, system, params_at_start[system - 1])
                               for system in SYSTEMS))
        assert_no_limit_below_its_floor(swarm)
        assert_alive(swarm, client)
