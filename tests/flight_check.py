"""After a storm of hostile traffic: put a vehicle back in order as a ground station would,
then prove it still flies, against the swarm's ground truth.

Putting it back in order means only what a client may do: every parameter back to the value
it had at start (PARAM_SET; in-range values are configuration), land if airborne, disarm,
HOLD. Then it must arm, take off, fly one waypoint by DO_REPOSITION and land there. Every
wait is bounded in simulated time, converted to wall time with the swarm's speed.
`assert_alive` and `assert_no_limit_below_its_floor` are the invariants a storm must keep.
"""

from __future__ import annotations

import asyncio
import math
import struct
import time
from collections.abc import Callable, Mapping

import pytest

from emulator.flight.modes import FlightMode
from emulator.flight.params import ParamStore
from emulator.swarm import Swarm
from tests.mavlink_client import MavClient, scheduler_alive, swarm_socket_open

__all__ = [
    "HOP_M", "assert_alive", "assert_no_limit_below_its_floor", "fly_one_waypoint",
    "recover_and_fly", "restore_params", "wait_truth",
]

ACCEPTED = 0
PARAM_TYPE_INT32, PARAM_TYPE_REAL32 = 6, 9
HOP_M = 15.0  # length of the waypoint leg
WALL_SLACK_S = 3.0  # scheduling and loopback delays on top of a simulated-time budget


async def wait_truth(swarm: Swarm, done: Callable[[], bool], sim_s: float, what: str) -> None:
    """Poll a ground-truth predicate until it holds; fail after sim_s of simulated time."""
    speed = swarm.clock.speed
    deadline = time.monotonic() + sim_s / speed + WALL_SLACK_S
    t0 = swarm.fleet.now_s
    while not done():
        if swarm.fleet.now_s - t0 > sim_s or time.monotonic() > deadline:
            raise AssertionError(f"{what}: not within {sim_s:.0f} s of simulated time")
        await asyncio.sleep(0.01)


def assert_no_limit_below_its_floor(swarm: Swarm) -> None:
    """No speed, rate, acceleration or acceptance limit below its parameter's range minimum."""
    dyn = swarm.fleet.dyn

    def floor(*names: str) -> float:
        return min(ParamStore.definition(name).minimum for name in names)

    assert (dyn.speed_xy_m_s >= floor("MPC_XY_CRUISE")).all(), dyn.speed_xy_m_s
    assert (dyn.airspeed_max_m_s >= floor("MPC_XY_VEL_MAX")).all(), dyn.airspeed_max_m_s
    assert (dyn.climb_m_s >= floor("MPC_Z_VEL_MAX_UP", "MPC_TKO_SPEED")).all(), dyn.climb_m_s
    assert (dyn.descent_m_s >= floor("MPC_Z_VEL_MAX_DN", "MPC_LAND_SPEED")).all()
    assert (dyn.accel_xy_m_s2 >= floor("MPC_ACC_HOR")).all()
    assert (dyn.accel_z_m_s2 >= floor("MPC_ACC_UP_MAX")).all()
    assert (dyn.yaw_rate_deg_s >= floor("MPC_YAWRAUTO_MAX")).all(), dyn.yaw_rate_deg_s
    assert (dyn.acceptance_m >= floor("NAV_ACC_RAD")).all()


def assert_alive(swarm: Swarm, client: MavClient) -> None:
    """No exception reached the event loop; scheduler, socket and handlers are sound."""
    errors = client.loop_errors
    assert errors is not None and not errors.errors, errors and errors.describe()
    assert scheduler_alive(swarm), "the scheduler task died"
    assert swarm_socket_open(swarm), "the swarm's socket was closed"
    assert swarm.stats().internal_errors == 0, "a handler or telemetry builder raised"


def _bytewise(value: float) -> float:
    return struct.unpack("<f", struct.pack("<i", int(value)))[0]


def _unbytewise(value: float) -> int:
    return struct.unpack("<i", struct.pack("<f", value))[0]


async def restore_params(client: MavClient, system: int, values: Mapping[str, float]) -> None:
    """PARAM_SET every parameter to `values` (ints bytewise as PX4); check each echo."""
    for name, value in values.items():
        if ParamStore.definition(name).is_int:
            echo = await client.param_set(system, name, _bytewise(value), PARAM_TYPE_INT32)
            assert _unbytewise(echo.param_value) == int(value), (system, name, echo.to_dict())
        else:
            echo = await client.param_set(system, name, value, PARAM_TYPE_REAL32)
            assert echo.param_value == pytest.approx(value, rel=1e-6), (system, name)


async def _land_and_disarm(client: MavClient, swarm: Swarm, system: int) -> None:
    ap = swarm.fleet.autopilots[system - 1]
    if ap.in_air:
        ack = await client.command_long(system, 21, *[math.nan] * 7)
        assert ack.result == ACCEPTED, (system, ack.to_dict())
        climb_m = max(ap.position_m[2], 0.0)
        await wait_truth(swarm, lambda: not ap.in_air, 60.0 + 2.0 * climb_m,
                         f"vehicle {system} landing")
    if ap.armed:
        ack = await client.command_long(system, 400, 0.0)
        assert ack.result == ACCEPTED, (system, ack.to_dict())
    assert not ap.armed and not ap.in_air
    ack = await client.command_long(system, 176, 1, 4, 3)  # AUTO.LOITER: out of any mission
    assert ack.result == ACCEPTED, (system, ack.to_dict())
    assert ap.mode is FlightMode.HOLD


def _waypoint_m(swarm: Swarm, system: int) -> tuple[float, float]:
    """HOP_M from where the vehicle is, towards home if the way is clear (else the first
    clear one of eight directions), so that the leg stays inside the geofence."""
    ap = swarm.fleet.autopilots[system - 1]
    x, y, z = ap.position_m
    heading = math.atan2(ap.home_m[1] - y, ap.home_m[0] - x)
    for turn in range(8):
        angle = heading + turn * math.pi / 4.0
        target = (x + HOP_M * math.cos(angle), y + HOP_M * math.sin(angle))
        if swarm.fleet.world.first_blockage((x, y, z), (*target, z)) is None:
            return target
    raise AssertionError(f"vehicle {system} is boxed in by obstacles at {(x, y, z)}")


async def fly_one_waypoint(client: MavClient, swarm: Swarm, system: int) -> None:
    """Arm, take off, DO_REPOSITION one hop away, land; each step checked in ground truth."""
    ap = swarm.fleet.autopilots[system - 1]
    vid = ap.vehicle_id
    t0 = swarm.fleet.now_s
    first = len(swarm.recorder.events(vid))
    assert (await client.command_long(system, 400, 1.0)).result == ACCEPTED
    ack = await client.command_long(system, 22, *[math.nan] * 7)
    assert ack.result == ACCEPTED, (system, ack.to_dict())
    climb_m = ap.home_m[2] + ap.params["MIS_TAKEOFF_ALT"]
    await wait_truth(swarm, lambda: bool(swarm.recorder.events(
        vid, t0_s=t0, kinds=("takeoff_complete",))), 20.0 + 2.0 * climb_m,
        f"vehicle {system} take-off")
    x, y = _waypoint_m(swarm, system)
    origin = swarm.fleet.world.origin
    lat, lon, _ = origin.to_geodetic(x, y, 0.0)
    ack = await client.command_int(system, 192, frame=0, p1=math.nan, p2=1.0,
                                   x=round(lat * 1e7), y=round(lon * 1e7), z=math.nan)
    assert ack.result == ACCEPTED, (system, ack.to_dict())

    def arrived() -> bool:
        px, py, _ = swarm.recorder.position_at(vid, swarm.fleet.now_s)
        return math.hypot(px - x, py - y) < 0.5 and swarm.fleet.dyn.speed_m_s(ap.k) < 0.3

    await wait_truth(swarm, arrived, 30.0 + 2.0 * HOP_M, f"vehicle {system} waypoint")
    t1 = swarm.fleet.now_s
    ack = await client.command_long(system, 21, *[math.nan] * 7)
    assert ack.result == ACCEPTED, (system, ack.to_dict())
    await wait_truth(swarm, lambda: bool(swarm.recorder.events(vid, t0_s=t1, kinds=("landed",))),
                     40.0 + 2.0 * climb_m, f"vehicle {system} landing")
    kinds = [e.kind for e in swarm.recorder.events(vid)[first:]
             if e.kind in ("arm", "takeoff", "takeoff_complete", "obstacle_stop", "landed")]
    assert kinds == ["arm", "takeoff", "takeoff_complete", "landed"], (system, kinds)
    landed = swarm.recorder.events(vid, t0_s=t1, kinds=("landed",))[-1]
    assert landed.data["position_m"][:2] == pytest.approx([x, y], abs=1.0)


async def recover_and_fly(client: MavClient, swarm: Swarm, system: int,
                          params_at_start: Mapping[str, float]) -> None:
    """Restore parameters, clear the plans (a fuzzed fence may enclose nothing), land/disarm
    if needed, then fly one waypoint."""
    await restore_params(client, system, params_at_start)
    client.send(client.mav.mission_clear_all_encode(system, 1, 255))  # MAV_MISSION_TYPE_ALL
    await client.wait_for("MISSION_ACK", system=system, where=lambda m: m.mission_type == 255)
    await _land_and_disarm(client, swarm, system)
    await fly_one_waypoint(client, swarm, system)
