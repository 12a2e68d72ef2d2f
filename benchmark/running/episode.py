"""One session of the benchmark: a stepped swarm, a gateway over MAVLink, and an agent given
the session's tasks in order.

Before each task, as the reference harness does: every drone is put down where it is, batteries
are refilled, inboxes emptied; positions and homes carry over. The agent gets the task text and
its tools and acts until it finishes or spends its budget; the hidden checks are then evaluated
on the ground truth of the task's window, with the clock held so nothing moves meanwhile. Each
task's record carries where the drones stood at its end, so a resumed run restores that layout
and continues exactly as an uninterrupted one.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import socket
import time
import traceback
from collections.abc import AsyncIterator, Callable, Mapping
from dataclasses import dataclass
from typing import Any

from agent_contract import Agent, AgentTask, AgentTools, BudgetExhausted
from benchmark.authoring.session_file import Session, TaskSpec
from benchmark.running.live_channel import LiveChannel, TaskWatch
from benchmark.running.replay_data import encode_window
from benchmark.running.task_record import record_key
from benchmark.running.tool_log import LoggedTools
from benchmark.scoring.validators import CheckContext, evaluate, leaf_count, tree_to_json
from emulator.clock import ClockConfig
from emulator.link_faults import LinkFaults
from emulator.networks import VEHICLES_PER_NETWORK
from emulator.services import SwarmServices
from emulator.swarm import PortPlan, Swarm
from mavlink_gateway import FleetConnection, Gateway, profiles_from_scenario
from mavlink_gateway.drone_link import LANDED_STATE_HZ
from mavlink_gateway.pacing import Thinker, run_as
from mavlink_vocabulary import FlightState

__all__ = ["BENCH_TELEMETRY_HZ", "CLOCKS", "EpisodeOptions", "base_record", "error_record",
           "record_key",
           "reset_for_task", "run_one_task", "run_session", "run_task", "session_link_faults",
           "session_swarm", "swarm_gateway"]

# Faster streams than a field autopilot's defaults: a primitive ends when telemetry shows its
# goal reached, and a reset when telemetry shows it, so wall time per task follows these rates.
BENCH_TELEMETRY_HZ = {"HEARTBEAT": 5.0, "EXTENDED_SYS_STATE": 5.0, "SYS_STATUS": 2.0,
                      "BATTERY_STATUS": 5.0, "HOME_POSITION": 1.0,
                      "GLOBAL_POSITION_INT": 20.0, "LOCAL_POSITION_NED": 1.0,
                      "ATTITUDE": 2.0, "GPS_RAW_INT": 0.5, "VFR_HUD": 1.0}
# Lockstep: outcomes are judged where the clock stops, on telemetry the swarm sends at once
# there, so the periodic streams only keep the links alive and the caches roughly current.
LOCKSTEP_TELEMETRY_HZ = {"HEARTBEAT": 1.0, "EXTENDED_SYS_STATE": 1.0, "SYS_STATUS": 1.0,
                         "BATTERY_STATUS": 1.0, "HOME_POSITION": 0.5,
                         "GLOBAL_POSITION_INT": 2.0, "LOCAL_POSITION_NED": 0.5,
                         "ATTITUDE": 0.5, "GPS_RAW_INT": 0.5, "VFR_HUD": 0.5}
POSITION_MSGS_PER_S = 300.0  # all drones together: what the gateway's MAVSDK keeps up with
RESET_SYNC_TIMEOUT_S = 20.0
RESET_RESEND_S = 0.25  # a drone whose telemetry still lags is asked again after this long
RESET_ASK_EVERY_S = 0.02  # at most one drone asked again this often
PLAY_OUT_WALL_S = 120.0
SETTLE_S = 1.0


# How simulated time passes while agents think (see emulator.clock): "lockstep" (the default)
# runs it only while every thread of the agent waits on the world, so results do not depend on
# model latency or machine load; "stepped" runs it whenever a drone executes a goal, so one
# drone's flight goes on while the agent thinks about another.
CLOCKS = ("lockstep", "stepped")


@dataclass(frozen=True)
class EpisodeOptions:
    trial: int = 0
    physics_hz: float = 50.0
    # a hung agent (no tool call and no simulated time for this many wall seconds) is stopped
    # and its task ends as an agent error (`_guarded`)
    agent_wall_timeout_s: float = 600.0
    clock: str = "lockstep"
    link_faults: Mapping[str, Any] | None = None  # LinkFaults.to_json(); else the session's

    def __post_init__(self) -> None:
        if self.clock not in CLOCKS:
            raise ValueError(f"unknown clock {self.clock!r} (known: {', '.join(CLOCKS)})")


def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def session_link_faults(session: Session, given: Mapping[str, Any] | None = None
                        ) -> LinkFaults | None:
    """The link faults a session runs with: `given` (a run's options), else the session
    file's ``link_faults``; None for a clean link."""
    raw = given if given is not None else session.data.get("link_faults")
    if raw is None:
        return None
    faults = LinkFaults.from_json(raw, f"{session.source}: link_faults",
                                  [v.id for v in session.scenario.vehicles])
    return None if faults.clean else faults


@contextlib.asynccontextmanager
async def swarm_gateway(session: Session, physics_hz: float = 50.0, *, lockstep: bool = False,
                        link_faults: LinkFaults | None = None,
                        ) -> AsyncIterator[tuple[Swarm, SwarmServices, Gateway]]:
    """A stepped (`lockstep`: lockstep) swarm for the session on 127.0.0.1 and a gateway
    connected over MAVLink (through `link_faults`, if any). The gateway speaks to one MAVLink
    network, so a session's swarm holds 1 to 250 vehicles (system ids 1-250)."""
    scenario = session.scenario
    if len(scenario.vehicles) > VEHICLES_PER_NETWORK:
        raise ValueError(f"a session's swarm holds 1 to {VEHICLES_PER_NETWORK} vehicles (one "
                         f"MAVLink network), got {len(scenario.vehicles)}")
    port = _free_udp_port()
    ports = PortPlan(bind_host="127.0.0.1", api_port=port, gcs_port=0)
    clock = ClockConfig(physics_hz=physics_hz, stepped=True, lockstep=lockstep)
    rates = dict(LOCKSTEP_TELEMETRY_HZ if lockstep else BENCH_TELEMETRY_HZ)
    rates["GLOBAL_POSITION_INT"] = min(rates["GLOBAL_POSITION_INT"],
                                       max(5.0, POSITION_MSGS_PER_S / len(scenario.vehicles)))
    async with Swarm(scenario, clock=clock, ports=ports, telemetry_hz=rates,
                     link_faults=link_faults) as swarm:
        services = SwarmServices(swarm)
        async with await FleetConnection.connect(
            f"udpin://127.0.0.1:{port}", profiles_from_scenario(scenario), scenario.world.origin,
            landed_state_hz=None if lockstep else LANDED_STATE_HZ,
            refresh=services.refresh_telemetry if lockstep else None,
        ) as fleet:
            yield swarm, services, Gateway(fleet.drones, services, connection=fleet)


def session_swarm(session: Session, options: EpisodeOptions
                  ) -> contextlib.AbstractAsyncContextManager[tuple[Swarm, SwarmServices, Gateway]]:
    """The swarm and gateway a run of `session` flies with `options` (clock, physics rate,
    link faults); raises ValueError when the session's world cannot fly."""
    faults = session_link_faults(session, options.link_faults)
    return swarm_gateway(session, options.physics_hz, lockstep=options.clock == "lockstep",
                         link_faults=faults)


async def reset_for_task(swarm: Swarm, services: SwarmServices, gateway: Gateway) -> None:
    """Land all, refill batteries, empty inboxes; wait until telemetry shows it."""
    services.operator_land_all()
    services.operator_reset_batteries(100.0)
    services.operator_clear_messages()
    await _sync_telemetry(swarm, gateway)


async def _sync_telemetry(swarm: Swarm, gateway: Gateway) -> None:
    fleet = swarm.fleet
    for link in gateway.drones.values():
        link.failure = None  # the operator's reset repaired every failed drone
    deadline = time.monotonic() + RESET_SYNC_TIMEOUT_S
    # The reset's telemetry goes out for every drone at once; a ground station's MAVSDK drops
    # subscription callbacks when such a burst overflows its queue (a large fleet), and a
    # lossy link loses some. Drones still lagging are asked again one by one, paced, so the
    # repeats themselves never overflow it.
    asked: dict[str, float] = {}
    next_ask = time.monotonic() + RESET_RESEND_S
    while True:
        lagging = []
        for ap in fleet.autopilots:
            link = gateway.drones[ap.vehicle_id]
            p = link.position_m
            if (p is None or math.dist(p, ap.position_m) > 0.1 or link.armed
                    or link.flight_state != FlightState.ON_GROUND or link.battery_pct < 99.0
                    or link.home_m is None or math.dist(link.home_m, ap.home_m) > 0.1):
                lagging.append(ap.vehicle_id)
        if not lagging:
            return
        now = time.monotonic()
        if now > deadline:
            raise RuntimeError(f"telemetry of {lagging} did not show the reset")
        if now >= next_ask:
            due = [d for d in lagging if now - asked.get(d, -math.inf) >= RESET_RESEND_S]
            if due:
                swarm.send_telemetry_of(due[0])
                asked[due[0]] = now
            next_ask = now + RESET_ASK_EVERY_S
        await asyncio.sleep(0.005)


async def _play_out(swarm: Swarm, deadline_s: float) -> float:
    """Let goals still under way finish (a take-off settling, a move the agent did not wait
    for), up to the task's simulated-time budget; the window ends then. This end does not
    depend on when, in wall time, the agent said it had finished."""
    hold = swarm.hold_clock_at(deadline_s)
    try:
        wall_deadline = time.monotonic() + PLAY_OUT_WALL_S
        while swarm.fleet.any_busy and swarm.fleet.now_s < deadline_s - 1e-9:
            if time.monotonic() > wall_deadline:
                break
            await asyncio.sleep(0.002)
    finally:
        swarm.release_clock(hold)
    # A goal ends once reached, not at a standstill: let every drone come to rest.
    await swarm.advance(SETTLE_S)
    return swarm.fleet.now_s


def base_record(*, session_id: str, family: str, level: str, task_id: str, template: str,
                category: str, agent: str, trial: int, fingerprint: str | None = None
                ) -> dict[str, Any]:
    """The fields that name a task's record; fingerprint: its session file's
    (benchmark.authoring.fingerprint), None when the session could not be read."""
    return {"key": record_key(session_id, task_id, agent, trial), "session": session_id,
            "family": family, "level": level, "task": task_id, "template": template,
            "category": category, "agent": agent, "trial": trial, "fingerprint": fingerprint}


def _base_record(session: Session, task: TaskSpec, agent: str, trial: int) -> dict[str, Any]:
    return base_record(session_id=session.id, family=session.family, level=session.level,
                       task_id=task.id, template=task.template, category=task.category,
                       agent=agent, trial=trial, fingerprint=session.fingerprint)


def error_record(base: Mapping[str, Any], error: str) -> dict[str, Any]:
    """A failed record for a task that could not be run (finish "task_error")."""
    return {**base, "passed": False, "checks": [], "checks_total": 0, "checks_passed": 0,
            "finish": "task_error", "error": error, "tool_calls": 0, "sim_time_s": 0.0,
            "wall_time_s": 0.0, "tokens": None, "overhead_s": {"reset": 0.0, "evaluate": 0.0}}


def task_error_record(session: Session, task: TaskSpec, agent: str, trial: int,
                      error: str) -> dict[str, Any]:
    return error_record(_base_record(session, task, agent, trial), error)


HUNG_POLL_S = 0.25  # how often the hang guard looks for progress
CANCEL_GRACE_S = 5.0  # how long a stopped agent may take to unwind


class AgentHung(Exception):
    """The agent made no tool call and let no simulated time pass for too long."""


async def _guarded(run: asyncio.Task[None], tools: AgentTools, services: SwarmServices,
                   timeout_s: float) -> None:
    """Await the agent's run; stop it once `timeout_s` wall seconds pass in which it made no
    tool call and simulated time did not move. An agent that acts, or waits on the world,
    never meets this guard, so no other record can depend on wall time; a hung one stops the
    lockstep clock (and an idle swarm's stepped one), so its budget would never run out."""
    progress = (tools.tool_calls, services.clock_s())
    idle_since = time.monotonic()
    while True:
        try:
            await asyncio.wait({run}, timeout=HUNG_POLL_S)
        except asyncio.CancelledError:  # the run itself is stopping: so does the agent
            run.cancel()
            raise
        if run.done():
            return run.result()
        now = (tools.tool_calls, services.clock_s())
        if now != progress:
            progress, idle_since = now, time.monotonic()
        elif time.monotonic() - idle_since >= timeout_s:
            break
    run.cancel()
    await asyncio.wait({run}, timeout=CANCEL_GRACE_S)
    run.add_done_callback(lambda t: t.cancelled() or t.exception())  # never "not retrieved"
    ignored = "" if run.done() else "; it ignored being cancelled"
    raise AgentHung(f"the agent made no tool call and simulated time did not advance for "
                    f"{timeout_s:g} s of wall time (--agent-timeout-s): stopped as hung{ignored}")


async def _run_agent(agent: Agent, task: AgentTask, tools: AgentTools,
                     options: EpisodeOptions, services: SwarmServices
                     ) -> tuple[str, str | None]:
    thinker = Thinker(services)  # the agent thinks first: the clock waits for it
    try:
        await _guarded(run_as(thinker, agent.run(task, tools)), tools, services,
                       options.agent_wall_timeout_s)
    except BudgetExhausted as spent:
        return spent.reason, str(spent)
    except AgentHung as hung:
        return "agent_error", str(hung)
    except Exception as error:  # a crashing agent ends its task, never the run
        where = traceback.extract_tb(error.__traceback__)[-1]
        return "agent_error", (f"{type(error).__name__}: {error} "
                               f"({where.filename.rsplit('/', 1)[-1]}:{where.lineno})")
    finally:
        thinker.close()
    if tools.spent is not None:
        return tools.spent.reason, str(tools.spent)
    return "finished", None


async def run_session(session: Session, agent: Agent, *, emit: Callable[[dict[str, Any]], None],
                      done: Mapping[str, Mapping[str, Any] | None] | None = None,
                      options: EpisodeOptions = EpisodeOptions(),
                      live: LiveChannel | None = None) -> None:
    """Run every task of `session` not already in `done` (key -> its end state, or None),
    calling `emit(record)` as each task ends; `live` publishes frames while it runs."""
    done = done or {}
    keys = [record_key(session.id, t.id, agent.name, options.trial) for t in session.tasks]
    if all(k in done for k in keys):
        return
    stack = contextlib.AsyncExitStack()
    try:
        swarm, services, gateway = await stack.enter_async_context(
            session_swarm(session, options))
    except ValueError as error:  # the world cannot fly (a vehicle parameter out of range...)
        await stack.aclose()
        for task, key in zip(session.tasks, keys, strict=True):
            if key not in done:
                emit(task_error_record(session, task, agent.name, options.trial,
                                       f"{session.source}: the session cannot start: {error}"))
        return
    async with stack:
        watch = None
        if live is not None:
            watch = await stack.enter_async_context(
                live.publishing(session, swarm, options.trial))
        restore: Mapping[str, Any] | None = None
        for task, key in zip(session.tasks, keys, strict=True):
            if key in done:
                restore = done[key] or restore
                continue
            if restore is not None:
                services.operator_restore(restore)
                restore = None
            if task.error is not None or task.checks is None or task.budget is None:
                emit(task_error_record(session, task, agent.name, options.trial,
                                       f"{session.source}: {task.error}"))
                continue
            emit(await run_task(session, task, agent, swarm, services, gateway, options,
                                watch=watch))


async def run_one_task(session: Session, task: TaskSpec, agent: Agent,
                       options: EpisodeOptions = EpisodeOptions(), *,
                       truth: Callable[[CheckContext], None] | None = None) -> dict[str, Any]:
    """One task alone on a swarm of its own, from the session's starting layout (as the first
    task of a run starts): its record, as `run_task` makes it, or a task_error record."""
    if task.error is not None or task.checks is None or task.budget is None:
        return task_error_record(session, task, agent.name, options.trial,
                                 f"{session.source}: {task.error}")
    stack = contextlib.AsyncExitStack()
    try:
        swarm, services, gateway = await stack.enter_async_context(
            session_swarm(session, options))
    except ValueError as error:
        await stack.aclose()
        return task_error_record(session, task, agent.name, options.trial,
                                 f"{session.source}: the session cannot start: {error}")
    async with stack:
        return await run_task(session, task, agent, swarm, services, gateway, options,
                              truth=truth)


async def run_task(session: Session, task: TaskSpec, agent: Agent, swarm: Swarm,
                   services: SwarmServices, gateway: Gateway,
                   options: EpisodeOptions, *, watch: TaskWatch | None = None,
                   truth: Callable[[CheckContext], None] | None = None
                   ) -> dict[str, Any]:
    """Reset, run the agent on one task, evaluate its checks; the task's record. Its
    `replay` (the window's ground truth and the tool calls, `benchmark.running.replay_data`) is
    stored
    apart from results.jsonl by the orchestrator. `truth`, if given, is handed the ground
    truth the checks were evaluated on, while the clock is still held at the window's end."""
    assert task.checks is not None and task.budget is not None
    wall0 = time.perf_counter()
    await reset_for_task(swarm, services, gateway)
    reset_s = time.perf_counter() - wall0
    agent_task = AgentTask(session.id, task.id, task.text, task.budget)
    tools = LoggedTools(gateway, agent_task)
    if watch is not None:
        watch.text, watch.tools = task.text, tools
    t0_s = services.clock_s()
    faults = task.faults
    if faults is not None:
        faults.apply(swarm, t0_s)
    wall_agent = time.perf_counter()
    finish, error = await _run_agent(agent, agent_task, tools, options, services)
    agent_wall_s = time.perf_counter() - wall_agent
    await tools.close()
    t1_s = await _play_out(swarm, t0_s + task.budget.sim_time_s)
    hold = swarm.hold_clock_at(t1_s)  # nothing moves between the end and the reset
    try:
        wall_eval = time.perf_counter()
        context = CheckContext(swarm.recorder, session.scenario, t0_s, t1_s)
        result = evaluate(task.checks, context)
        eval_s = time.perf_counter() - wall_eval
        if truth is not None:
            truth(context)
        end_state = services.operator_snapshot()
        replay = encode_window(swarm.recorder, t0_s, t1_s, tools.call_log())
        replay.update(tools.transcript_json())
        replay["task"] = {"text": task.text, "checks": tree_to_json(task.checks),
                          "budget": {"tool_calls": task.budget.tool_calls,
                                     "sim_time_s": task.budget.sim_time_s}}
        if faults is not None:
            faults.end(swarm, session_link_faults(session, options.link_faults))
        services.operator_land_all()  # before the clock may run again
    finally:
        swarm.release_clock(hold)
    leaves = [leaf.to_json() for leaf in result.leaves]
    tokens = None
    if tools.prompt_tokens or tools.completion_tokens:
        tokens = {"prompt": tools.prompt_tokens, "completion": tools.completion_tokens,
                  "cost_usd": round(tools.cost_usd, 6)}
    return {**_base_record(session, task, agent.name, options.trial),
            "passed": result.passed, "checks": leaves,
            "checks_total": leaf_count(task.checks),
            "checks_passed": sum(1 for leaf in result.leaves if leaf.passed),
            "finish": finish, "error": error, "tool_calls": tools.tool_calls,
            "clock": options.clock,
            "sim_time_s": round(t1_s - t0_s, 3), "wall_time_s": round(agent_wall_s, 3),
            "tokens": tokens,
            "overhead_s": {"reset": round(reset_s, 4), "evaluate": round(eval_s, 4)},
            "end_state": end_state, "window_s": [round(t0_s, 3), round(t1_s, 3)],
            "replay": replay}
