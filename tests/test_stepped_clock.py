"""The stepped clock's bookkeeping on a fleet without sockets: how far the scheduler may step,
holds, and the callers it wakes."""

from __future__ import annotations

import asyncio
import math

from emulator.flight.fleet import Fleet
from emulator.scenario import default_scenario
from emulator.stepped_clock import MAX_STEPS_PER_RUN, SteppedClock


def _fleet() -> Fleet:
    return Fleet(default_scenario(2), physics_hz=50.0)


def test_an_idle_fleet_steps_only_towards_a_target_and_never_past_a_hold() -> None:
    fleet = _fleet()
    wakes: list[int] = []
    clock = SteppedClock(fleet, lambda: wakes.append(1))
    assert not clock.should_step([])  # at rest, no target
    assert clock.should_step([1.0])
    assert clock.steps_allowed([1.0]) == 50  # 1 s at 50 Hz
    token = clock.hold_at(0.5)
    assert clock.held_at() == 0.5
    assert clock.steps_allowed([1.0]) == 25
    clock.release(token)
    assert wakes == [1]  # a release wakes the scheduler
    assert clock.held_at() == math.inf
    clock.release(token)  # twice: nothing more
    assert wakes == [1]
    pin = clock.hold_at(fleet.now_s)
    assert not clock.should_step([1.0])  # pinned where it stands
    clock.release(pin)


def test_a_busy_fleet_runs_at_most_a_run_and_stops_at_the_nearest_target() -> None:
    fleet = _fleet()
    fleet.autopilots[0].arm()
    fleet.autopilots[0].takeoff(10.0)
    assert fleet.any_busy
    clock = SteppedClock(fleet, lambda: None)
    assert clock.should_step([])
    assert clock.steps_allowed([]) == MAX_STEPS_PER_RUN
    assert clock.steps_allowed([2.0, math.inf, -1.0]) == 100
    assert clock.steps_allowed([0.0]) == MAX_STEPS_PER_RUN  # a target reached is no limit


async def test_callers_wake_when_the_clock_reaches_their_target_or_rest() -> None:
    fleet = _fleet()
    clock = SteppedClock(fleet, lambda: None)
    await clock.wait_idle()  # at rest: at once
    advanced = asyncio.create_task(clock.advance_to(0.1))
    await asyncio.sleep(0)
    assert clock.should_step([])  # its target lies ahead
    assert clock.steps_allowed([]) == 5
    clock.release_waiters()
    assert not advanced.done()
    fleet.run(5)
    clock.release_waiters()
    await asyncio.wait_for(advanced, 1.0)
    assert not clock.should_step([])
    pending = asyncio.create_task(clock.advance_to(5.0))
    await asyncio.sleep(0)
    clock.cancel_waiters()
    await asyncio.sleep(0)
    assert pending.cancelled()
