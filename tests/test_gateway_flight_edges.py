"""The gateway's flight primitives at their edges, against the real emulator over real UDP
(MAVSDK): five drones at once and a busy drone's refusal, a primitive that runs out of
simulated time, a wind beyond the airframe, the critical-battery failsafe, telemetry slower
than the clock, moves within the acceptance radius and a landing seen through slow positions.
Each outcome is checked against the emulator's ground truth, as in test_gateway_flight.py.
"""

from __future__ import annotations

import asyncio
import math
from collections.abc import Awaitable
from typing import Any

import numpy as np
import pytest

from emulator.world import Wind
from mavlink_gateway import Outcome, Status
from mavlink_gateway.flight import ARRIVAL_M
from tests.gateway_fixtures import GatewaySession, assert_consistent, gateway_session, near
from tests.scenario_fixtures import tiny_scenario, vehicle

pytestmark = pytest.mark.mavsdk


async def _all_busy_then(s: Any, calls: list[Awaitable[Outcome]]) -> list[Outcome]:
    """The outcomes of `calls`, made at once with the stepped clock stopped until every
    drone is busy (or every call has answered)."""
    pin = s.swarm.pin()
    try:
        together = asyncio.gather(*calls)
        while not s.swarm.fleet.busy.all() and not together.done():
            await asyncio.sleep(0.001)
    finally:
        s.swarm.release_clock(pin)
    return await together


async def test_five_drones_fly_concurrently_and_a_busy_drone_refuses():
    drones = [vehicle(k, 5.0 * (k - 1), 0.0) for k in range(1, 6)]
    async with gateway_session(tiny_scenario(drones), telemetry_hz=None) as s:
        gw = s.gw
        ids = [f"d{k}" for k in range(1, 6)]
        # The clock is pinned until all five climb: stepped, the first drones' climbs would
        # otherwise run out the last one's time while a loaded machine arms it in wall time.
        outs = await _all_busy_then(s, [gw.take_off(d, 10 + 2 * i) for i, d in enumerate(ids)])
        assert [o.status for o in outs] == [Status.OK] * 5, outs

        goals = {d: (5.0 * i + 100.0 * math.sin(i * 1.2), 100.0 * math.cos(i * 1.2), 15.0)
                 for i, d in enumerate(ids)}
        t0 = s.now_s
        # Pinned again until all five fly, for the same reason.
        outs = await _all_busy_then(s, [gw.move_to(d, *goals[d]) for d in ids])
        assert [o.status for o in outs] == [Status.OK] * 5, outs
        elapsed = s.now_s - t0
        spans = []
        for d, out in zip(ids, outs, strict=True):
            assert out.message == f"{d} reached ({goals[d][0]:.1f}, {goals[d][1]:.1f}, 15.0)"
            assert_consistent(s, out, d, tolerance_m=ARRIVAL_M)
            near(s, d, goals[d])
            traj = s.swarm.recorder.trajectory(d, t0)
            moving = np.flatnonzero(np.linalg.norm(np.diff(traj[:, 1:4], axis=0), axis=1) > 1e-3)
            spans.append((traj[moving[0], 0], traj[moving[-1] + 1, 0]))
        # Concurrent, not one after the other: all five were in flight at the same time, and
        # the whole took about one ~100 m flight.
        assert max(a for a, _ in spans) < min(b for _, b in spans)
        assert elapsed < 2 * (100.0 / 8.0 + 10.0)

        # A second primitive for a drone that is still busy is refused; others go on. The
        # clock is pinned until then: stepped, the whole move may take less wall time than
        # one look at the busy flag.
        pin = s.swarm.pin()
        fly = asyncio.create_task(gw.move_to("d1", 0, 0, 15))
        while not s.swarm.fleet.busy[0]:
            await asyncio.sleep(0.001)
        t1 = s.now_s
        second = await gw.hover("d1", 5)
        s.swarm.release_clock(pin)
        assert second.status is Status.REJECTED
        assert second.message == "drone d1 is busy with move_to: wait for it to end"
        assert second.state is not None and second.state.drone == "d1"
        # What does not fly is not serialised: state, perception and radio still answer.
        assert gw.drone_state("d1").ok and gw.nearby("d1").ok
        assert gw.send_message("d1", "d2", "on my way").ok
        other = await gw.move_to("d2", 0, 50, 20)
        assert other.ok
        assert (await fly).ok
        assert not s.swarm.recorder.events("d1", t0_s=t1, kinds=["mission_start"])
        near(s, "d1", (0.0, 0.0, 15.0))
        assert (await gw.hover("d1", 1)).ok


async def test_a_primitive_that_runs_out_of_time_ends_and_holds():
    # A headwind of 11.8 m/s against a 12 m/s airframe leaves 0.2 m/s over the ground: 100 m
    # would take 500 s, far beyond the move's budget (100 m / 5 m/s * 2 + 30 s = 70 s). The
    # clock is stepped, not lockstep, so it runs on while the gateway notices the budget is
    # spent: the flight must outlast the budget by more than a fast machine's clock covers
    # in that wall time (at 3,000x, 10 ms of wall time are 30 simulated seconds).
    sc = tiny_scenario([vehicle(1)], wind=Wind(11.8, 90.0))
    async with gateway_session(sc) as s:
        gw, ap = s.gw, s.ap("d1")
        assert (await gw.take_off("d1", 10)).ok
        t0 = s.now_s
        out = await gw.move_to("d1", 100, 0, 10)
        assert out.status is Status.TIMEOUT
        assert out.message == ("move_to did not finish within 70 s of simulated time; "
                               "holding")
        assert 70.0 - 1e-6 <= s.now_s - t0 < 500.0
        assert out.state is not None and out.state.drone == "d1"
        # The primitive ended and so did its goal: the drone holds short of the goal and
        # the stepped clock stops (nothing runs on while the caller thinks).
        await s.settle()
        assert ap.mode.name == "HOLD" and ap.in_air and ap.position_m[0] < 98.0
        t1, where = s.now_s, ap.position_m
        await asyncio.sleep(0.3)
        assert s.now_s == t1 and ap.position_m == where
        assert (await gw.move_to("d1", 0, 0, 10)).ok  # and it still flies


async def test_take_off_in_a_wind_beyond_the_airframe_times_out_below_its_goal():
    # 16 m/s of wind against a 12 m/s airframe: it drifts and cannot hold its take-off point.
    sc = tiny_scenario([vehicle(1)], wind=Wind(16.0, 90.0))
    async with gateway_session(sc) as s:
        t0 = s.now_s
        out = await s.gw.take_off("d1", 10)
        assert out.status is Status.TIMEOUT
        assert out.message.startswith("take_off did not finish within 40 s of simulated time")
        traj = s.swarm.recorder.trajectory("d1", t0)
        assert traj[-1, 1] < -50.0  # blown west
        # Climbing stops at the goal altitude even while drifting (the fast-forward through
        # steady flight must not extrapolate a climb that is not aimed at the goal).
        assert traj[:, 3].max() <= 10.05


async def test_critical_battery_failsafe_stops_a_move():
    async with gateway_session(tiny_scenario([vehicle(1)])) as s:
        gw, ap = s.gw, s.ap("d1")
        assert (await gw.take_off("d1", 10)).ok
        s.services.operator_reset_batteries(7.3)
        await s.settle()
        t0 = s.now_s
        # Stepped, the clock runs on while the outcome travels to the gateway; held 15 s on
        # (the critical level comes about 3 s on), it cannot reach the emergency level first.
        hold = s.swarm.hold_clock_at(t0 + 15.0)
        out = await gw.move_to("d1", 300, 0, 10)
        assert out.status is Status.BLOCKED
        assert out.message.startswith("move_to stopped: Critical battery 7%: returning home")
        failsafes = s.swarm.recorder.events("d1", t0_s=t0, kinds=["failsafe"])
        assert [e.data["reason"] for e in failsafes] == ["battery_critical"]
        assert ap.mode.name == "RTL" and ap.position_m[0] < 100.0
        s.swarm.release_clock(hold)


async def _race_once_in(s: GatewaySession, mode: str, t0_s: float) -> None:
    """Run d1's clock flat out to 600 s on, as other drones' flights would, once its command
    has reached it (it entered `mode`). Racing from before, the clock could run the budget out
    while the command itself travels, which on a loaded machine takes long enough."""
    def entered() -> bool:
        return any(e.data.get("mode") == mode
                   for e in s.swarm.recorder.events("d1", t0_s=t0_s, kinds=["mode"]))

    while not entered():
        await asyncio.sleep(0.001)
    await s.services.advance(600.0)


async def test_outcomes_hold_when_the_clock_outruns_telemetry():
    # In stepped mode the clock runs as fast as it can while anything keeps it busy (here a
    # caller advancing it, as other drones' flights would): telemetry at its default wall
    # rates (landed state 1 Hz) then lags by many simulated seconds. A take-off or landing
    # that succeeded must not be reported as out of time because the news came late.
    async with gateway_session(tiny_scenario([vehicle(1)]), telemetry_hz=None) as s:
        gw, ap = s.gw, s.ap("d1")
        for call, message, budget, mode in [
            (lambda: gw.take_off("d1", 10), "d1 took off to 10.0 m", 40.0, "takeoff"),
            (lambda: gw.land("d1"), "d1 landed at (0.0, 0.0)", 50.0, "land"),
        ]:
            await s.settle()
            t0 = s.now_s
            racing = asyncio.create_task(_race_once_in(s, mode, t0))
            out = await call()
            await racing
            assert out.status is Status.OK and out.message == message, out
            assert s.now_s - t0 > budget  # the budget did run out while the news travelled
        assert not ap.in_air
        kinds = [e.kind for e in s.swarm.recorder.events("d1")]
        assert kinds.count("takeoff_complete") == 1 and kinds.count("landed") == 1


async def test_short_moves_within_the_acceptance_radius_still_fly():
    # NAV_ACC_RAD is 2 m: goals closer than that to a drone at rest must still be flown to,
    # not counted as reached before it moves.
    async with gateway_session(tiny_scenario([vehicle(1)])) as s:
        gw, ap = s.gw, s.ap("d1")
        out = await asyncio.wait_for(gw.take_off("d1", 1.5), 15.0)
        assert out.status is Status.OK and out.message == "d1 took off to 1.5 m"
        assert ap.position_m[2] == pytest.approx(1.5, abs=0.1)
        out = await asyncio.wait_for(gw.move_to("d1", 1.5, 0, 1.5), 15.0)
        assert out.status is Status.OK and out.message == "d1 reached (1.5, 0.0, 1.5)"
        near(s, "d1", (1.5, 0.0, 1.5), 0.1)
        out = await asyncio.wait_for(gw.change_altitude("d1", 2.5), 15.0)
        assert out.status is Status.OK
        near(s, "d1", (1.5, 0.0, 2.5), 0.1)
        kinds = [e.kind for e in s.swarm.recorder.events("d1")]
        assert kinds.index("takeoff_complete") > kinds.index("takeoff")
        complete = s.swarm.recorder.events("d1", kinds=["takeoff_complete"])[0]
        assert complete.data["position_m"][2] == pytest.approx(1.5, abs=0.1)


async def test_landing_is_reported_from_the_ground_even_with_slow_positions():
    # Landed state at 10 Hz, positions at 1 Hz: the landed state reaches the gateway first
    # (a stepped-mode descent takes a few wall milliseconds). The outcome must still give the
    # drone on the ground, not at the altitude of the last position before the descent.
    async with gateway_session(tiny_scenario([vehicle(1)])) as s:
        gw, link = s.gw, s.link("d1")
        assert (await gw.take_off("d1", 15)).ok
        await link.telemetry.set_rate_position(1.0)
        out = await gw.land("d1")
        assert out.status is Status.OK, out
        assert_consistent(s, out, "d1")
        assert out.state.altitude_m == pytest.approx(0.0, abs=0.3)
        assert (await gw.take_off("d1", 15)).ok
        assert (await gw.move_to("d1", 30, 0, 15)).ok
        out = await gw.return_home("d1")
        assert out.status is Status.OK and out.state.altitude_m == pytest.approx(0.0, abs=0.3)
        assert_consistent(s, out, "d1")
