"""The oracle agent: executes a task's hidden plan (see benchmark.authoring.templates.base for the
operations) through `AgentTools`, planning obstacle-free paths over the world it knows."""

from __future__ import annotations

import asyncio
import concurrent.futures
import logging
import math
from collections.abc import Awaitable, Callable, Mapping, Sequence
from functools import partial
from typing import Any, assert_never

from agent_contract import AgentTask, AgentTools
from benchmark.authoring.plan_steps import (
    Altitude,
    Broadcast,
    Charge,
    DroneStep,
    Goto,
    Home,
    Hover,
    Intercept,
    Land,
    Meet,
    Message,
    Photo,
    PhotoTarget,
    Plan,
    Reach,
    Rotate,
    SetHome,
    Step,
    Sweep,
    Takeoff,
    Towards,
    Track,
    UntilFault,
    VisitTargets,
    Waypoints,
    parse_plan,
)
from benchmark.scoring.validators.tree import Node
from emulator.scenario import Scenario
from mavlink_gateway import Outcome, Status
from mavlink_vocabulary import FlightState
from swarm_agents.oracle.approach import approach_point, leg_start
from swarm_agents.oracle.coverage import lawnmower, order_visits, split_lanes
from swarm_agents.oracle.derive import Unplannable, derive_plan
from swarm_agents.oracle.planner import NoPath, PathPlanner
from swarm_agents.oracle.pursuit import Pursuit

__all__ = ["OracleAgent", "OracleCannotPlan", "OracleError"]

log = logging.getLogger(__name__)

SWEEP_SPACING_SHARE = 1.6  # lane spacing as a multiple of the task radius
CHARGE_ALTITUDE_M = 15.0
MAX_PATH_POINTS = 100
# Paths keep this far from obstacles, so tracking errors never meet the 2 m stop margin.
PLAN_CLEARANCE_M = 8.0
# Meeting a moving target: the share of top speed assumed and the slack added to a flight.
MEET_SPEED_SHARE = 0.8
MEET_SLACK_S = 8.0
PLANNING_THREAD = "oracle-planning"  # the name (prefix) of the oracle's planning thread
CRUISE_M_S = 8.0  # the autopilot's MPC_XY_CRUISE: move_to flies at most this fast
MIN_HOVER_S = 0.2
HOP_S = 4.0  # following: aim this far ahead of the target
FOLLOW_EXTRA_S = 2.0
TRANSFER_RETRIES = 2
TRANSFER_LOST = ("TIMEOUT", "upload restarted")
CLOSE_IN_TRIES = 4
# A directed leg blocked where the drone is starts from the nearest clear spot of these rings.
LEG_RING_M = 15.0
LEG_RINGS = 20
LEG_RING_SPOTS = 16
LEG_SLACK_M = 15.0
# A move that collision prevention stopped short (wind drift into an obstacle's margin) is
# planned again from where the drone holds, at most this many times.
DRIFT_REPLANS = 2


def _point(p: Sequence[float]) -> tuple[float, float, float]:
    return float(p[0]), float(p[1]), float(p[2])


async def _retried(call: Callable[[], Awaitable[Outcome]]) -> Outcome:
    """A move whose mission or command the link lost on the way (a transfer time-out under
    load) is sent again, as any client would; other outcomes are final."""
    outcome = await call()
    for _ in range(TRANSFER_RETRIES):
        lost = outcome.status is Status.REJECTED and any(
            word in outcome.message for word in TRANSFER_LOST)
        if not lost:
            break
        outcome = await call()
    return outcome


def _stopped_by_obstacle(outcome: Outcome) -> bool:
    return outcome.status is Status.BLOCKED and "obstacle" in outcome.message.lower()


class OracleError(RuntimeError):
    """Raised when the oracle cannot carry out its plan (a refused or failed primitive)."""


class OracleCannotPlan(RuntimeError):
    """Raised by run when a task has no hand plan and none can be derived from its checks:
    the task's record ends as agent_error with the leaf and the reason."""


Op = Mapping[str, Any]  # a step as plans are written (see benchmark.authoring.plan_steps)


class OracleAgent:
    """Flies the hidden plan of each task of one session."""

    name = "oracle"

    def __init__(self, scenario: Scenario, plans: Mapping[str, Sequence[Sequence[Op]]],
                 *, checks: Mapping[str, Node] | None = None,
                 faulted: Mapping[str, Sequence[str]] | None = None,
                 derived_only: bool = False) -> None:
        """plans: hand-written plans by task id; checks: check trees to derive a plan from
        when a task has none (or always, with derived_only); faulted: by task id, the drones
        its hidden faults strike (given no optional work in derived plans)."""
        self._scenario = scenario
        self._world = scenario.world
        self._plans = dict(plans)
        self._checks = dict(checks or {})
        self._faulted = dict(faulted or {})
        self.derived_only = derived_only
        self._planner = PathPlanner(scenario.world, clearance_m=PLAN_CLEARANCE_M)
        self._specs = {v.id: v for v in scenario.vehicles}
        self._pursuit = Pursuit(scenario.world)
        # Paths and meeting points are worked out on a thread of their own, one at a time:
        # the event loop (the swarm, the gateway, the other drones' threads) keeps running
        # meanwhile, so no wall-clock wait elsewhere sees a stalled loop as a silent drone.
        self._planning = concurrent.futures.ThreadPoolExecutor(1, PLANNING_THREAD)
        self.failures: list[str] = []

    def set_plan(self, task_id: str, plan: Sequence[Sequence[Op]] | None) -> None:
        """Give (or replace) the hidden plan of one task (as session files write it)."""
        if plan is None:
            self._plans.pop(task_id, None)
        else:
            self._plans[task_id] = plan

    def set_checks(self, task_id: str, checks: Node, faulted: Sequence[str] = ()) -> None:
        """Give (or replace) the check tree a plan is derived from for one task."""
        self._checks[task_id] = checks
        self._faulted[task_id] = list(faulted)

    def derive(self, task_id: str) -> Sequence[Sequence[Op]]:
        """A plan derived from the task's checks and the drones' last known states."""
        checks = self._checks.get(task_id)
        if checks is None:
            raise OracleCannotPlan(f"task {task_id} has neither a reference plan nor checks")
        try:
            return derive_plan(checks, self._scenario, self._state,
                               faulted=self._faulted.get(task_id, ()))
        except Unplannable as error:
            raise OracleCannotPlan(str(error)) from None

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        listing = tools.list_drones()
        self._state = {d["drone"]: d for d in (listing.data or {}).get("drones", [])}
        plan = None if self.derived_only else self._plans.get(task.task_id)
        if plan is None:
            plan = self.derive(task.task_id)
        try:
            steps = parse_plan(plan, f"task {task.task_id} plan")
        except ValueError as error:
            raise OracleCannotPlan(str(error)) from None
        await self._run_plan(task, tools, steps)

    async def _run_plan(self, task: AgentTask, tools: AgentTools, plan: Plan) -> None:
        for phase in plan:
            queues: dict[str, list[DroneStep]] = {}
            for step in phase:
                for drone, drone_step in self._expand(step):
                    queues.setdefault(drone, []).append(drone_step)
            results = await tools.concurrently(
                *(self._run_queue(tools, drone, ops) for drone, ops in queues.items()))
            for result in results:
                if isinstance(result, OracleError):
                    self.failures.append(str(result))
                    log.warning("oracle: %s: %s", task.task_id, result)
                elif isinstance(result, BaseException):
                    raise result
        tools.finish("plan executed")

    # ------------------------------------------------------------- expansion
    def _expand(self, step: Step) -> list[tuple[str, DroneStep]]:
        match step:
            case Sweep():
                return self._expand_sweep(step)
            case VisitTargets():
                return self._expand_visits(step)
        return [(step.drone, step)]

    def _xy(self, drone: str) -> tuple[float, float]:
        s = self._state[drone]
        return float(s["x_m"]), float(s["y_m"])

    def _expand_sweep(self, step: Sweep) -> list[tuple[str, DroneStep]]:
        drones = list(step.drones)
        target = self._world.target(step.target)
        radius = min(self._specs[d].task_radius_m for d in drones)
        points = lawnmower(target.geometry, step.altitude_m,
                           SWEEP_SPACING_SHARE * radius, start_xy=self._xy(drones[0]))
        pieces = split_lanes(points, len(drones))
        return [(d, Waypoints(drone=d, points=tuple(_point(p) for p in piece)))
                for d, piece in zip(drones, pieces, strict=True) if piece]

    def _expand_visits(self, step: VisitTargets) -> list[tuple[str, DroneStep]]:
        drones = list(step.drones)
        alt = step.altitude_m
        goals = {t: self._target_point(t) for t in step.targets}
        ends = {d: self._xy(d) for d in drones}
        loads = dict.fromkeys(drones, 0.0)
        assigned: dict[str, list[str]] = {d: [] for d in drones}
        remaining = list(goals)
        while remaining:  # greedy: the cheapest (drone, target) extension each round
            best = min((loads[d] + math.dist(ends[d], goals[t]), d, t)
                        for d in drones for t in remaining)
            cost, d, t = best
            loads[d], ends[d] = cost, goals[t]
            assigned[d].append(t)
            remaining.remove(t)
        out: list[tuple[str, DroneStep]] = []
        for d, targets in assigned.items():
            if not targets:
                continue
            order = order_visits(self._xy(d), [goals[t] for t in targets])
            points = tuple((*goals[targets[i]], alt) for i in order)
            out.append((d, Waypoints(drone=d, points=points)))
        return out

    def _target_point(self, target_id: str) -> tuple[float, float]:
        target = self._world.target(target_id)
        if target.kind == "polygon":
            centroid = target.geometry.centroid
            inside = target.geometry.contains(centroid)
            p = centroid if inside else target.geometry.representative_point()
            return float(p.x), float(p.y)
        return float(target.position_m[0]), float(target.position_m[1])

    # ------------------------------------------------------------- execution
    async def _run_queue(self, tools: AgentTools, drone: str, steps: list[DroneStep]) -> None:
        for step in steps:
            await self._run_step(tools, drone, step)

    def _check(self, drone: str, what: str, outcome: Outcome) -> Outcome:
        if outcome.state is not None:
            self._state[drone] = outcome.state.to_dict()
        if outcome.status is not Status.OK:
            raise OracleError(f"{drone} {what}: {outcome.status.value}: {outcome.message}")
        return outcome

    def _airborne(self, drone: str) -> bool:
        return self._state[drone]["flight_state"] != FlightState.ON_GROUND

    async def _run_step(self, tools: AgentTools, d: str, step: DroneStep) -> None:
        kind = step.op
        match step:
            case Takeoff(altitude_m=alt):
                if self._airborne(d):
                    self._check(d, kind, await tools.change_altitude(d, alt))
                else:
                    self._check(d, kind, await tools.take_off(d, alt))
            case Goto(x=x, y=y, z=z):
                await self._goto(tools, d, (x, y, z))
            case Waypoints(points=points):
                await self._path(tools, d, list(points))
            case Land():
                self._check(d, kind, await tools.land(d))
            case Hover(duration_s=duration_s):
                self._check(d, kind, await tools.hover(d, duration_s))
            case Rotate(heading_deg=heading_deg):
                self._check(d, kind, await tools.rotate(d, heading_deg))
            case Altitude(altitude_m=alt):
                self._check(d, kind, await tools.change_altitude(d, alt))
            case Towards(heading_deg=heading_deg, distance_m=distance_m):
                await self._towards(tools, d, heading_deg, distance_m)
            case Photo():
                self._check(d, kind, await tools.take_photo(d))
            case SetHome():
                self._check(d, kind, await tools.set_home(d))
            case Home(altitude_m=alt):
                s = self._state[d]
                await self._goto(tools, d, (float(s["home_x_m"]), float(s["home_y_m"]), alt))
                self._check(d, "land at home", await tools.land(d))
            case Charge(station=station):
                x, y = self._target_point(station)
                await self._goto(tools, d, (x, y, CHARGE_ALTITUDE_M))
                self._check(d, "land on the station", await tools.land(d))
                self._check(d, kind, await tools.charge(d))
                self._state[d]["flight_state"] = FlightState.ON_GROUND  # charged only there
            case Message(to=to, text=text):
                self._check(d, kind, tools.send_message(d, to, text))
            case Broadcast(text=text):
                self._check(d, kind, tools.broadcast(d, text))
            case Reach(target=target, altitude_m=alt):
                x, y = self._target_point(target)
                await self._goto(tools, d, (x, y, alt))
            case Track(target=target, duration_s=duration_s, altitude_m=alt):
                met_s = await self._meet(tools, d, target, alt)
                await self._follow(tools, d, target, alt, met_s + duration_s)
            case Intercept(target=target, zone=zone, altitude_m=alt):
                await self._meet(tools, d, target, alt, zone=zone)
            case UntilFault(altitude_m=alt, duration_s=duration_s):
                await self._until_fault(tools, d, alt, duration_s)
            case Meet(target=target, altitude_m=alt):
                await self._meet(tools, d, target, alt)
            case PhotoTarget(target=target, altitude_m=alt):
                await self._meet(tools, d, target, alt)
                self._check(d, "photo", await tools.take_photo(d))
            case _:
                assert_never(step)

    async def _until_fault(self, tools: AgentTools, d: str, altitude_m: float,
                           duration_s: float) -> None:
        """Take off and hold while the task's scheduled fault strikes the drone: the fault
        ends it (a failed, unknown or interrupted outcome is what the plan expects)."""
        if not self._airborne(d):
            outcome = await tools.take_off(d, max(altitude_m, 5.0))
            if outcome.state is not None:
                self._state[d] = outcome.state.to_dict()
            if outcome.status is not Status.OK:
                return
        outcome = await tools.hover(d, duration_s)
        if outcome.state is not None:
            self._state[d] = outcome.state.to_dict()

    # ------------------------------------------------------------- moving targets
    async def _meet(self, tools: AgentTools, d: str, target: str, altitude_m: float,
                    zone: tuple[float, float, float] | None = None) -> float:
        """Fly to where the target will be (inside the zone, if given) and hover there until
        it arrives; returns the simulated time of the meeting (when the drone came late, the
        time it arrived)."""
        await self._ensure_airborne(tools, d, altitude_m)
        now = tools.clock_s
        here = self._position(d)
        speed = min(self._specs[d].max_speed_m_s, CRUISE_M_S)

        def flight_s(goal: tuple[float, float]) -> float:
            legs = self._plan_legs(here, (goal[0], goal[1], altitude_m))
            length = sum(math.dist(a, b) for a, b in zip([here, *legs[:-1]], legs,
                                                          strict=True))
            return length / (MEET_SPEED_SHARE * speed) + MEET_SLACK_S

        def lower_s(goal: tuple[float, float]) -> float:
            straight = math.dist(here, (goal[0], goal[1], altitude_m))
            return straight / (MEET_SPEED_SHARE * speed) + MEET_SLACK_S

        try:
            meet_s = await self._planned(self._pursuit.meeting, target, now, flight_s, lower_s,
                                         zone)
        except ValueError as error:
            raise OracleError(f"{d}: {error}") from None
        x, y = await self._planned(self._pursuit.xy, target, meet_s)
        await self._goto(tools, d, (x, y, altitude_m))
        wait_s = meet_s - tools.clock_s
        if wait_s > MIN_HOVER_S:
            self._check(d, "wait for the target", await tools.hover(d, wait_s))
        return max(meet_s, tools.clock_s)

    async def _follow(self, tools: AgentTools, d: str, target: str, altitude_m: float,
                      until_s: float) -> None:
        """Stay on the target until until_s: aim at where it will be HOP_S later, wait."""
        while tools.clock_s < until_s + FOLLOW_EXTRA_S:
            aim_s = tools.clock_s + HOP_S
            x, y = await self._planned(self._pursuit.xy, target, aim_s)
            self._check(d, "follow", await _retried(partial(tools.move_to, d, x, y, altitude_m)))
            wait_s = aim_s - tools.clock_s
            if wait_s > MIN_HOVER_S:
                self._check(d, "follow", await tools.hover(d, wait_s))

    def _position(self, d: str) -> tuple[float, float, float]:
        s = self._state[d]
        return float(s["x_m"]), float(s["y_m"]), float(s["altitude_m"])

    async def _towards(self, tools: AgentTools, d: str, heading_deg: float,
                       distance_m: float) -> None:
        if self._airborne(d):
            here = self._position(d)
            start = leg_start(self._planner, here, heading_deg, distance_m)
            if start != here[:2]:
                await self._goto(tools, d, (start[0], start[1], here[2]))
        self._check(d, "towards", await tools.move_towards(d, heading_deg, distance_m))

    async def _ensure_airborne(self, tools: AgentTools, d: str, altitude_m: float) -> None:
        if not self._airborne(d):
            self._check(d, "take-off", await tools.take_off(d, max(altitude_m, 5.0)))

    async def _close_in(self, tools: AgentTools, d: str, goal: tuple[float, float, float],
                        error: NoPath) -> None:
        """A goal the planner cannot reach (nearer an obstacle than its clearance): fly to
        a spot near it, then straight at it; collision prevention stops the drone where it
        must, and the checks judge how close that is."""
        spot = approach_point(self._planner, self._position(d), goal)
        if spot is None:
            raise OracleError(f"no path from {self._position(d)} to {goal}: {error}")
        await self._goto(tools, d, spot)
        for _ in range(CLOSE_IN_TRIES):  # each stop is nearer: the drone starts slower
            outcome = await _retried(partial(tools.move_to, d, *goal))
            if outcome.state is not None:
                self._state[d] = outcome.state.to_dict()
            if outcome.status is not Status.BLOCKED:
                self._check(d, "move", outcome)
                return

    async def _planned(self, work: Callable[..., Any], *args: Any) -> Any:
        """work(*args) on the planning thread (see __init__)."""
        return await asyncio.get_running_loop().run_in_executor(self._planning, work, *args)

    async def _legs(self, start: tuple[float, float, float], goal: tuple[float, float, float]
                    ) -> list[tuple[float, float, float]]:
        return list(await self._planned(self._plan_legs, start, goal))

    def _plan_legs(self, start: tuple[float, float, float], goal: tuple[float, float, float]
                   ) -> list[tuple[float, float, float]]:
        try:
            return self._planner.plan(start, goal)
        except NoPath as error:
            raise OracleError(f"no path from {start} to {goal}: {error}") from None

    async def _goto(self, tools: AgentTools, d: str, goal: tuple[float, float, float]) -> None:
        await self._ensure_airborne(tools, d, goal[2])
        for attempt in range(DRIFT_REPLANS + 1):
            try:
                waypoints = await self._planned(self._planner.plan, self._position(d), goal)
            except NoPath as error:
                await self._close_in(tools, d, goal, error)
                return
            if len(waypoints) == 1:
                what, outcome = "move", await _retried(partial(tools.move_to, d, *goal))
            else:
                what, outcome = "path", await self._flown_waypoints(tools, d, waypoints)
            if attempt < DRIFT_REPLANS and _stopped_by_obstacle(outcome):
                # Wind carried the drone off its leg into an obstacle's margin: plan again
                # from where collision prevention held it.
                if outcome.state is not None:
                    self._state[d] = outcome.state.to_dict()
                continue
            self._check(d, what, outcome)
            return

    async def _path(self, tools: AgentTools, d: str,
                    points: list[tuple[float, ...]]) -> None:
        if not points:
            return
        first = points[0]
        await self._ensure_airborne(tools, d, first[2])
        waypoints: list[tuple[float, float, float]] = []
        here = self._position(d)
        for p in points:
            goal = (p[0], p[1], p[2])
            waypoints.extend(await self._legs(here, goal))
            here = goal
        await self._fly_waypoints(tools, d, waypoints)

    async def _fly_waypoints(self, tools: AgentTools, d: str,
                             waypoints: list[tuple[float, float, float]]) -> None:
        self._check(d, "path", await self._flown_waypoints(tools, d, waypoints))

    async def _flown_waypoints(self, tools: AgentTools, d: str,
                               waypoints: list[tuple[float, float, float]]) -> Outcome:
        """Fly the waypoints, MAX_PATH_POINTS per mission; the first outcome that is not OK,
        else the last."""
        outcome = None
        for k in range(0, len(waypoints), MAX_PATH_POINTS):
            chunk = [list(w) for w in waypoints[k:k + MAX_PATH_POINTS]]
            outcome = await _retried(partial(tools.move_along_path, d, chunk))
            if outcome.status is not Status.OK:
                return outcome
            if outcome.state is not None:
                self._state[d] = outcome.state.to_dict()
        assert outcome is not None, "no waypoints to fly"
        return outcome
