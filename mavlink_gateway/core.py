"""Plumbing shared by every primitive: drone lookup, one primitive per drone at a time,
precondition checks, and waiting for an outcome within a simulated-time budget."""

from __future__ import annotations

import inspect
import math
import time
from collections.abc import Awaitable, Callable, Mapping
from typing import TYPE_CHECKING, Any

from mavlink_gateway.command_send import Acted, NoAnswer, Refusal, send_command
from mavlink_gateway.drone_link import PERIODIC, DroneLink
from mavlink_gateway.effects import holding
from mavlink_gateway.goals import Goal, Interrupted
from mavlink_gateway.interfaces import Services
from mavlink_gateway.lockstep_wait import (
    ARRIVED_SPEED_M_S,
    judge_failure,
    settle_telemetry,
    wait_instant,
    wait_lockstep,
)
from mavlink_gateway.outcomes import Outcome, Status
from mavlink_vocabulary import GOAL_ENDING_MESSAGES, FlightState, ObstacleHold, parse_statustext

if TYPE_CHECKING:
    from mavlink_gateway.fleet import FleetConnection

__all__ = ["GatewayCore", "Interrupted", "NoAnswer", "Refusal"]

POLL_S = 0.01  # longest wait between two looks at an outcome when no telemetry arrives
WALL_MARGIN_S = 60.0
LANDED_Z_M = 0.3  # the ground is z = 0 of the local frame everywhere
FRESH_WAIT_S = 3.0  # wall time to wait for every periodic stream (battery is 0.5 Hz)
# A look at the world now (an interrupted goal, a refusal that may answer a repeat): these
# streams, sent after the look began
JUDGED_STREAMS = ("position", "velocity", "landed_state", "in_air", "flight_mode")
JUDGE_WALL_S = 1.5  # the heartbeat (armed, mode) is 1 Hz by default


def no_answer_outcome(link: DroneLink, name: str, error: NoAnswer) -> Outcome:
    return Outcome(Status.UNKNOWN, f"{name}: {error}; the drone may or may not have acted "
                   f"(state as last seen)", link.state())


def _number(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise Refusal(f"{name} must be a finite number, got {_short(value)}")
    try:
        number = float(value)  # an int beyond float range raises OverflowError
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        raise Refusal(f"{name} must be a finite number, got {_short(value)}")
    return number


def _short(value: object, limit: int = 60) -> str:
    """repr() of a caller's argument for a message: shortened, and never raising (repr of an
    int of more than 4300 digits raises ValueError)."""
    try:
        text = repr(value)
    except Exception:
        text = f"<{type(value).__name__}>"
    return text if len(text) <= limit else text[:limit - 3] + "..."


class GatewayCore:
    """Drone lookup, per-drone serialisation and outcome waits."""

    def __init__(self, drones: Mapping[str, DroneLink], services: Services, *,
                 connection: FleetConnection | None = None) -> None:
        self.drones = dict(drones)
        self.services = services
        # The MAVLink connection the links came from: drones joining the swarm are discovered
        # on it (Gateway.add_drone); None where the drones are fixed.
        self.connection = connection
        self._busy: dict[str, str] = {}
        self._goals: dict[str, Goal] = {}
        # The primitive that a replacing primitive interrupted, while the latter runs.
        self._replaced: dict[str, str] = {}
        # Simulated time of each drone's last command: a stepped clock runs on while the
        # answer travels back, so an outcome's budget starts there, not when the wait begins.
        self._command_s: dict[str, float] = {}

    def busy_with(self, drone: str) -> str | None:
        """The primitive running for `drone` now (None: none)."""
        return self._busy.get(drone)

    # --------------------------------------------------------------- lookup
    def _link(self, drone: object) -> DroneLink:
        link = self.drones.get(drone) if isinstance(drone, str) else None
        if link is None:
            ids = list(self.drones)
            known = f"{ids[0]} to {ids[-1]}" if len(ids) > 3 else ", ".join(ids)
            raise Refusal(f"unknown drone {_short(drone)} (known: {known})")
        return link

    async def _run(self, name: str, drone: object,
                   body: Callable[[DroneLink], Awaitable[Outcome]], *,
                   replace: bool = False) -> Outcome:
        """Run one primitive for one drone. A second one for the same drone is refused, or
        with `replace` it interrupts the running one (which ends with Status.INTERRUPTED),
        HOLD is sent, and then this one runs."""
        try:
            link = self._link(drone)
        except Refusal as refusal:
            return Outcome(Status.REJECTED, str(refusal))
        replaced: str | None = None
        held = False
        while (current := self._busy.get(link.drone_id)) is not None:
            if not replace:
                return Outcome(Status.REJECTED,
                               f"drone {link.drone_id} is busy with {current}: wait for it to "
                               f"end", link.state())
            replaced = current
            held = await self._interrupt(link.drone_id, name)
        if link.failure is not None:
            return Outcome(Status.FAILED, f"{name}: drone {link.drone_id} is out of the task: "
                           f"{link.failure}", link.state())
        self._busy[link.drone_id] = name
        goal = self._goals[link.drone_id] = Goal(name)
        try:
            if replaced is not None:
                self._replaced[link.drone_id] = replaced
                if not held:
                    await self._mavsdk(link, f"hold (to end {replaced})", link.action.hold,
                                       holding)
            return await body(link)
        except Refusal as refusal:
            return Outcome(Status.REJECTED, f"{name} refused: {refusal}", link.state())
        except NoAnswer as error:
            return no_answer_outcome(link, name, error)
        except Interrupted as stop:
            return Outcome(Status.INTERRUPTED, f"{name} interrupted by {stop.by}: "
                           f"{link.drone_id} no longer pursues its goal", link.state())
        finally:
            del self._busy[link.drone_id]
            del self._goals[link.drone_id]
            self._replaced.pop(link.drone_id, None)
            self._command_s.pop(link.drone_id, None)  # a wait that never came drops it
            goal.ended.set()

    async def _interrupt(self, drone_id: str, by: str) -> bool:
        """Ask the primitive running for `drone_id` to end, and wait until it has: it ends
        at its next look at the world (sending HOLD itself), or once the command in flight is
        answered (a command is never abandoned half-sent: a late copy would undo the hold).
        True if it sent HOLD."""
        goal = self._goals.get(drone_id)
        if goal is None:
            return False
        goal.interrupt(by)
        await goal.ended.wait()
        return goal.held

    def _goal(self, link: DroneLink) -> Goal | None:
        return self._goals.get(link.drone_id)

    # -------------------------------------------------------- preconditions
    @staticmethod
    def _require_air(link: DroneLink) -> None:
        if link.flight_state == FlightState.ON_GROUND:
            raise Refusal(f"drone {link.drone_id} is on the ground: take off first")

    @staticmethod
    def _altitude(link: DroneLink, value: object, name: str = "altitude") -> float:
        altitude = _number(name, value)
        ceiling = link.profile.max_altitude_m
        if altitude > ceiling:
            raise Refusal(f"{name} {altitude:g} m exceeds this drone's ceiling of {ceiling:g} m")
        if altitude < 1.0:
            raise Refusal(f"{name} {altitude:g} m is below the 1 m minimum flight altitude")
        return altitude

    @staticmethod
    def _coordinate(name: str, value: object) -> float:
        coordinate = _number(name, value)
        if abs(coordinate) > 100_000.0:
            raise Refusal(f"{name} {coordinate:g} m is beyond the 100 km map limit")
        return coordinate

    async def _mavsdk(self, link: DroneLink, what: str, call: Callable[[], Awaitable[Any]],
                      acted: Acted | None = None, *, repeatable: bool = False) -> None:
        """Send a command (see mavlink_gateway.command_send); `acted` tells whether fresh
        telemetry shows its effect, for a refusal that may answer a repeat; a `repeatable`
        one is made again instead."""
        def sent() -> None:
            # A budget starts when the command that counts was sent (the last try's).
            self._command_s[link.drone_id] = self.services.clock_s()

        await send_command(link, what, call, goal=self._goal(link), sent=sent,
                           refresh=lambda: self._fresh_telemetry(link), acted=acted,
                           repeatable=repeatable)

    # ----------------------------------------------------------------- waits
    async def _wait(self, link: DroneLink, budget_s: float, what: str,
                    done: Callable[[], Outcome | Awaitable[Outcome | None] | None], *,
                    watch_obstacles: bool = True, texts_from: int | None = None,
                    instant: bool = False, fresh: tuple[str, ...] = PERIODIC) -> Outcome:
        """Wait for an outcome (see `_wait_for_outcome`); a stepped clock is held at the
        budget's end, so a time-out happens at exactly `budget_s` of simulated time. With a
        lockstep clock, the outcome is judged where the clock stops (see
        mavlink_gateway.lockstep_wait). `instant`: the outcome needs no simulated time.
        `fresh`: the telemetry streams judged anew once the budget has run out (a stepped
        clock: see `_wait_for_outcome`)."""
        try:
            if self.services.lockstep:
                if instant:
                    return await wait_instant(link, what, done, budget_s)
                texts = len(link.status_texts) if texts_from is None else texts_from
                return await wait_lockstep(self.services, link, budget_s, what, done,
                                           self._hold, watch_obstacles=watch_obstacles,
                                           texts=texts, goal=self._goal(link))
            now = self.services.clock_s()
            start = min(self._command_s.pop(link.drone_id, now), now)
            with self.services.clock_limit(start + budget_s):
                return await self._wait_for_outcome(link, budget_s, what, done,
                                                    watch_obstacles=watch_obstacles,
                                                    texts_from=texts_from, start_s=start,
                                                    fresh=fresh)
        except Interrupted:
            # No command is in flight here: HOLD at once, then judge once more on telemetry
            # sent after it (telemetry lags the vehicle: the goal may have been reached
            # before the hold).
            goal = self._goal(link)
            held = await self._hold(link)
            if goal is not None:
                goal.held = held
            outcome = await self._judge_now(link, done)
            if outcome is not None:
                return outcome
            raise

    async def _fresh_telemetry(self, link: DroneLink) -> bool:
        """Wait for telemetry sent after this call (a lockstep clock stands still: the swarm
        is asked for it); False if none came within JUDGE_WALL_S."""
        if self.services.lockstep:
            self.services.refresh_telemetry(link.drone_id)
            return await settle_telemetry(link, self.services)
        mark, deadline = dict(link.seen), time.monotonic() + JUDGE_WALL_S
        while not link.refreshed_since(mark, JUDGED_STREAMS):
            if time.monotonic() >= deadline:
                return False
            await link.wait_update(link.updates, POLL_S)
        return True

    async def _judge_now(self, link: DroneLink,
                         done: Callable[[], Outcome | Awaitable[Outcome | None] | None]
                         ) -> Outcome | None:
        """`done()` on telemetry sent after this call."""
        await self._fresh_telemetry(link)
        try:
            outcome = done()
            if inspect.isawaitable(outcome):
                outcome = await outcome
        except Exception:  # a MAVSDK query that got no answer: not judged
            return None
        return outcome

    async def _wait_for_outcome(
        self, link: DroneLink, budget_s: float, what: str,
        done: Callable[[], Outcome | Awaitable[Outcome | None] | None], *,
        watch_obstacles: bool = True, texts_from: int | None = None,
        start_s: float | None = None, fresh: tuple[str, ...] = PERIODIC,
    ) -> Outcome:
        """Look at telemetry until `done` gives an outcome, an obstacle or failsafe stops the
        drone, or `budget_s` of simulated time has passed. Looks again as soon as a new
        telemetry message has been applied (at the latest after POLL_S).

        `texts_from`: the number of STATUSTEXTs before the command was sent. A goal blocked
        at once is reported within a physics step, and its STATUSTEXT may come before the
        command's ACK, so before this wait begins. `start_s`: the simulated time the budget
        started (default: now)."""
        texts = len(link.status_texts) if texts_from is None else texts_from
        start_sim = self.services.clock_s() if start_s is None else start_s
        wall_deadline = time.monotonic() + budget_s + WALL_MARGIN_S
        obstacle_mark: dict[str, int] | None = None  # telemetry seen when the obstacle text came
        goal = self._goal(link)
        while True:
            seen = link.updates
            outcome = done()
            if inspect.isawaitable(outcome):
                outcome = await outcome
            if outcome is not None:
                return outcome
            if goal is not None:
                goal.check()
            new_texts = link.status_texts[texts:]
            failure = judge_failure(link, what, texts)
            if failure is not None:
                return failure
            for text in new_texts:
                if isinstance(parse_statustext(text), GOAL_ENDING_MESSAGES):
                    return Outcome(Status.BLOCKED, f"{what} stopped: {text}", link.state())
            if watch_obstacles and obstacle_mark is None and \
                    any(isinstance(parse_statustext(t), ObstacleHold) for t in new_texts):
                obstacle_mark = dict(link.seen)
            # The text comes the moment the vehicle stops; speed, mode and position come at
            # their own rates and may still describe the start of the move (in stepped mode a
            # whole flight can fit between two positions): judge on telemetry sent after it.
            if obstacle_mark is not None and \
                    link.refreshed_since(obstacle_mark, ("position", "velocity"), 2) and \
                    link.speed_m_s < ARRIVED_SPEED_M_S and link.mode == "HOLD":
                x, y, z = link.position_m or (math.nan,) * 3
                obstacle = next(t for t in new_texts
                                if isinstance(parse_statustext(t), ObstacleHold))
                return Outcome(Status.BLOCKED, f"{what} stopped at ({x:.1f}, {y:.1f}, {z:.1f}): "
                               f"{obstacle.lower()}", link.state())
            elapsed = self.services.clock_s() - start_sim
            if elapsed >= budget_s - 1e-9 or time.monotonic() > wall_deadline:
                # The primitive ends here, so its goal must end too: left flying, the vehicle
                # would go on after the outcome (and a stepped clock would run while the
                # caller thinks). Best effort: the outcome is a timeout either way.
                held = await self._hold(link)
                # Telemetry lags the simulation (in stepped mode, while other drones keep the
                # clock running, seconds of wall time are minutes of simulated time): the goal
                # may have been reached long ago. Judge again on telemetry sent from now on.
                mark, fresh_deadline = dict(link.seen), time.monotonic() + FRESH_WAIT_S
                while not link.refreshed_since(mark, fresh) and \
                        time.monotonic() < fresh_deadline:
                    await link.wait_update(link.updates, POLL_S)
                outcome = done()
                if inspect.isawaitable(outcome):
                    outcome = await outcome
                if outcome is not None:
                    return outcome
                return Outcome(Status.TIMEOUT, f"{what} did not finish within {budget_s:.0f} s "
                               f"of simulated time{'; holding' if held else ''}", link.state())
            await link.wait_update(seen, POLL_S)

    async def _show_mode(self, link: DroneLink, mode: str) -> None:
        """Wait (briefly, in wall time) until telemetry shows the mode the drone was just put
        in; a lockstep clock stands still meanwhile, so the swarm is asked for its state."""
        if self.services.lockstep:
            self.services.refresh_telemetry(link.drone_id)
            await settle_telemetry(link, self.services)
            return
        deadline = time.monotonic() + FRESH_WAIT_S
        while link.mode != mode and time.monotonic() < deadline:
            await link.wait_update(link.updates, POLL_S)

    @staticmethod
    async def _hold(link: DroneLink) -> bool:
        """Switch an airborne drone to HOLD (it brakes and stays); True if it was sent. An
        armed drone is held even where telemetry still says it is on the ground: early in a
        take-off the climb has begun before telemetry tells it."""
        if link.flight_state == FlightState.ON_GROUND and not link.armed:
            return False
        try:
            await link.action.hold()
        except Exception:  # MAVSDK raises one error class per plugin
            return False
        return True

    @staticmethod
    def _landed(link: DroneLink) -> bool:
        """On the ground by the landed state and by the position. The landed state and the
        position come in different messages: in stepped mode a whole descent fits between two
        positions, and an outcome built on the landed state alone could report a landed drone
        still at its flight altitude."""
        pos = link.position_m
        return link.flight_state == FlightState.ON_GROUND and pos is not None and \
            pos[2] < LANDED_Z_M

    @staticmethod
    def _arrived(link: DroneLink, target: tuple[float, float, float], tolerance_m: float
                 ) -> bool:
        pos = link.position_m
        return (pos is not None and math.dist(pos, target) <= tolerance_m
                and link.speed_m_s < ARRIVED_SPEED_M_S and link.mode in ("HOLD", "MISSION"))
