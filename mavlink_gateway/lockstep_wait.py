"""Waiting for an outcome under a lockstep clock.

The swarm stops its clock at the physics step in which the watched drone's goal ends (or a
failsafe takes it over, or the budget runs out) and sends that drone's whole telemetry at once.
The wait then judges the outcome on telemetry that shows the stopped state, so the outcome,
and the simulated time at which the caller goes on, are the same on every run whatever the
wall-clock delays. The calling thread's pin on the clock is let go for the wait and taken back
at its end (see mavlink_gateway.pacing).
"""

from __future__ import annotations

import asyncio
import inspect
import math
import time
from collections.abc import Awaitable, Callable

from mavlink_gateway.drone_link import DroneLink
from mavlink_gateway.goals import Goal
from mavlink_gateway.interfaces import Services
from mavlink_gateway.outcomes import Outcome, Status
from mavlink_gateway.pacing import current_thinker
from mavlink_vocabulary import (
    GOAL_ENDING_MESSAGES,
    OUT_OF_TASK_MESSAGES,
    ObstacleHold,
    parse_statustext,
)

__all__ = ["judge_failure", "judge_stop", "settle_telemetry", "wait_instant", "wait_lockstep",
           "wait_world"]

SETTLE_WALL_S = 5.0  # a link that shows no settled state by then is judged as it is
TEXT_GRACE_S = 0.2  # a halt that explains nothing: time for a STATUSTEXT still on its way
POLL_S = 0.01
REBURST_WALL_S = 0.15  # telemetry lost on the way: ask the swarm for the stopped state again
REJUDGE_ROUNDS = 2  # a halt that shows no outcome is looked at again this many times
# The autopilot reports a goal reached once below 0.3 m/s; telemetry carries velocity in whole
# cm/s per axis, which can read a little higher. A stepped clock stops right then.
ARRIVED_SPEED_M_S = 0.5

Done = Callable[[], Outcome | Awaitable[Outcome | None] | None]


async def settle_telemetry(link: DroneLink, services: Services | None = None) -> bool:
    """Wait until every periodic stream of `link` shows the state of the stopped clock; False
    if no telemetry at all came meanwhile (the drone is silent). Telemetry lost on the way
    (a lossy link) is asked for again every REBURST_WALL_S."""
    mark = dict(link.seen)
    updates = link.updates
    start = time.monotonic()
    deadline, reburst = start + SETTLE_WALL_S, start + REBURST_WALL_S
    while not link.settled_since(mark) and time.monotonic() < deadline:
        await link.wait_update(link.updates, POLL_S)
        if services is not None and time.monotonic() > reburst:
            services.refresh_telemetry(link.drone_id)
            reburst = time.monotonic() + REBURST_WALL_S
    return link.updates != updates


def judge_failure(link: DroneLink, what: str, texts: int) -> Outcome | None:
    """A failure that takes the drone out (a motor, its GPS), reported since `texts`."""
    failure = next((t for t in link.status_texts[texts:]
                    if isinstance(parse_statustext(t), OUT_OF_TASK_MESSAGES)), None)
    if failure is None:
        return None
    return Outcome(Status.FAILED, f"{what} ended: {failure}; the drone is out of the task",
                   link.state())


async def _done(done: Done) -> Outcome | None:
    outcome = done()
    if inspect.isawaitable(outcome):
        try:
            outcome = await outcome
        except Exception:  # a MAVSDK query that got no answer: not judged this time
            return None
    return outcome


def judge_stop(link: DroneLink, what: str, texts: int, watch_obstacles: bool
               ) -> Outcome | None:
    """A failure, a failsafe or an obstacle stop seen in settled telemetry, else None."""
    failure = judge_failure(link, what, texts)
    if failure is not None:
        return failure
    new_texts = link.status_texts[texts:]
    for text in new_texts:
        if isinstance(parse_statustext(text), GOAL_ENDING_MESSAGES):
            return Outcome(Status.BLOCKED, f"{what} stopped: {text}", link.state())
    obstacle = next((t for t in new_texts if isinstance(parse_statustext(t), ObstacleHold)),
                    None)
    if watch_obstacles and obstacle is not None and link.speed_m_s < ARRIVED_SPEED_M_S \
            and link.mode == "HOLD":
        x, y, z = link.position_m or (math.nan,) * 3
        return Outcome(Status.BLOCKED, f"{what} stopped at ({x:.1f}, {y:.1f}, {z:.1f}): "
                       f"{obstacle.lower()}", link.state())
    return None


async def wait_lockstep(services: Services, link: DroneLink, budget_s: float, what: str,
                        done: Done, hold: Callable[[DroneLink], Awaitable[bool]], *,
                        watch_obstacles: bool, texts: int, goal: Goal | None = None
                        ) -> Outcome:
    """Wait for the outcome of the goal `link`'s drone is executing, halt by halt; raises
    Interrupted as soon as `goal` is interrupted."""
    watch = services.watch(link.drone_id, until_s=services.clock_s() + budget_s)
    thinker = current_thinker()
    if thinker is not None:
        thinker.wait()
    try:
        while True:
            await _halted_or_stopped(watch.halted(), goal)
            if not await settle_telemetry(link, services):
                return Outcome(Status.UNKNOWN, f"{what}: {link.drone_id} stopped answering (no "
                               f"telemetry for {SETTLE_WALL_S:g} s); its state is as last seen",
                               link.state())
            outcome = await _done(done) or judge_stop(link, what, texts, watch_obstacles)
            if outcome is None and not watch.at_deadline:
                await _text_grace(link)
                outcome = judge_stop(link, what, texts, watch_obstacles)
            for _ in range(REJUDGE_ROUNDS if outcome is None and not watch.at_deadline else 0):
                # Telemetry that showed nothing may be stale (messages lost on the way, or
                # dropped by a client under load): the clock stands still, so ask for the
                # state again, and for the texts of this instant, before letting it run on.
                outcome = await _ask_again(services, link, texts, done, what, watch_obstacles)
                if outcome is not None:
                    break
            if outcome is not None:
                return outcome
            if watch.at_deadline:
                held = await hold(link)  # the clock stands still: HOLD acts at the deadline
                services.refresh_telemetry(link.drone_id)
                await settle_telemetry(link, services)
                outcome = await _done(done)
                if outcome is not None:
                    return outcome
                return Outcome(Status.TIMEOUT, f"{what} did not finish within {budget_s:.0f} s "
                               f"of simulated time{'; holding' if held else ''}", link.state())
            watch.resume()
    finally:
        if thinker is not None:
            thinker.think()  # at the halt's time, before the watch lets the clock go
        watch.close()


async def _ask_again(services: Services, link: DroneLink, texts: int, done: Done, what: str,
                     watch_obstacles: bool) -> Outcome | None:
    """The halted drone's telemetry and STATUSTEXTs sent again (a text already here is not
    recorded twice), then judged."""
    link.repeats_since = texts
    try:
        received = link.texts_received
        services.refresh_telemetry(link.drone_id)
        repeated = services.repeat_status_texts(link.drone_id)
        await settle_telemetry(link, services)
        deadline = time.monotonic() + TEXT_GRACE_S
        while link.texts_received < received + repeated and time.monotonic() < deadline:
            await link.wait_update(link.updates, POLL_S)
        return await _done(done) or judge_stop(link, what, texts, watch_obstacles)
    finally:
        link.repeats_since = None


async def _halted_or_stopped(halted: Awaitable[float], goal: Goal | None) -> None:
    """Wait for the watch's halt; raise Interrupted once `goal` is stopped first."""
    if goal is None:
        await halted
        return
    goal.check()
    halt = asyncio.ensure_future(halted)
    stop = asyncio.ensure_future(goal.stop.wait())
    try:
        await asyncio.wait((halt, stop), return_when=asyncio.FIRST_COMPLETED)
    finally:
        for task in (halt, stop):
            task.cancel()  # the watch's halt is shielded: cancelling the wait is safe
    if halt.done() and not halt.cancelled():
        halt.result()
        return
    goal.check()


async def _text_grace(link: DroneLink) -> None:
    deadline = time.monotonic() + TEXT_GRACE_S
    count = len(link.status_texts)
    while len(link.status_texts) == count and time.monotonic() < deadline:
        await link.wait_update(link.updates, POLL_S)


async def wait_instant(link: DroneLink, what: str, done: Done, wall_s: float) -> Outcome:
    """Wait for an outcome that needs no simulated time (a photo, a new home): the clock
    stays where it is, pinned by the caller, while the answer travels."""
    deadline = time.monotonic() + wall_s
    while True:
        seen = link.updates
        outcome = await _done(done)
        if outcome is not None:
            return outcome
        if time.monotonic() > deadline:
            return Outcome(Status.TIMEOUT, f"{what}: no answer from the drone within "
                           f"{wall_s:g} s", link.state())
        await link.wait_update(seen, POLL_S)


async def wait_world(services: Services, drone_id: str, duration_s: float) -> tuple[float, bool]:
    """Let up to `duration_s` of simulated time pass for the caller, ending early once a radio
    message for `drone_id` can be read; (simulated seconds waited, whether a message came)."""
    start_s = services.clock_s()
    if not services.lockstep:
        await services.advance(duration_s)
        return services.clock_s() - start_s, False
    watch = services.watch(None, until_s=start_s + duration_s, advance=True,
                           message_for=drone_id)
    thinker = current_thinker()
    if thinker is not None:
        thinker.wait()
    try:
        halted_s = await watch.halted()
        return halted_s - start_s, halted_s < start_s + duration_s - 1e-9
    finally:
        if thinker is not None:
            thinker.think()
        watch.close()


