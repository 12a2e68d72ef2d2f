"""Runs an agent over benchmark sessions into a resumable JSON Lines results file.

Each (session, trial) is one unit of work, run by `run_unit` with its own swarm and ports,
wherever the backend puts it (`benchmark/running/backends.py`: this process, local worker processes,
or Ray tasks on a cluster). Units send each task's record back as the task ends; this process
alone appends to the results file, one whole line at a time, and never a key twice.
Re-running the same command skips every task already recorded and restores the layout the
last one left.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import time
from collections.abc import Awaitable, Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from agent_contract import Agent, AgentOptions
from benchmark.authoring.importer import load_any_session
from benchmark.authoring.session_file import Session, SessionFileError, read_session_json
from benchmark.running.backends import Handle, Unit, make_backend
from benchmark.running.episode import EpisodeOptions, base_record, error_record, run_session
from benchmark.running.hosted import EXTERNAL
from benchmark.running.live_channel import LiveChannel
from benchmark.running.progress import LineProgress, ProgressSink, task_line
from benchmark.running.replay_data import session_world, write_task_replay
from benchmark.running.results import ResultsLog, read_task_records
from benchmark.running.run_order import run_order, session_heads
from benchmark.running.worker_count import AUTO, auto_workers, shares_processes
from emulator.reference_mapping import notes_to_show
from mavlink_gateway import set_mavsdk_log
from swarm_agents import plugins

__all__ = [
    "AGENTS",
    "PlanWork",
    "RunOutcome",
    "RunPlan",
    "check_session_files",
    "make_agent",
    "run_benchmark",
    "run_unit",
    "run_unit_async",
]

# The built-in agents; NAME:per-drone: one instance of NAME per drone
# (swarm_agents.teams.per_drone).
# --agent also takes plug-ins (swarm_agents.plugins: package.module:Name, path/to/file.py:Name,
# installed entry points), which these lists do not hold.
PER_DRONE = plugins.PER_DRONE
AGENTS = (*plugins.BUILTIN_AGENTS, *(n + PER_DRONE for n in plugins.LLM_AGENTS))
LLM_AGENTS = tuple(n for n in AGENTS if n.removesuffix(PER_DRONE) in plugins.LLM_AGENTS)


@dataclass(frozen=True)
class RunPlan:
    sessions: tuple[Path, ...]
    agent: str = "oracle"
    trials: int = 1
    workers: int | str = 1  # sessions at once, or "auto" (benchmark.running.worker_count)
    out_dir: Path = Path("runs/bench")
    task_limit: int | None = None  # only the first N tasks of each session (smoke runs)
    physics_hz: float = 50.0
    clock: str = "lockstep"  # see benchmark.running.episode.CLOCKS
    model: str = ""  # LLM agents: model name and OpenAI-compatible base URL (else from the
    base_url: str = ""  # environment: OPENAI_MODEL, OPENAI_BASE_URL; key: OPENAI_API_KEY)
    price_in_usd_per_mtok: float = 0.0  # token prices for the cost per task (else from
    price_out_usd_per_mtok: float = 0.0  # MAVSWARM_PRICE_IN / MAVSWARM_PRICE_OUT)
    backend: str = "local"  # where units run: "local" (processes here) or "ray" (a cluster)
    ray_address: str = ""  # the Ray cluster to join (else Ray's own rules; see ray_backend)
    mavsdk_log: bool = False  # print MAVSDK's own log lines in the units (mavsdk_log.py)
    live_hz: float = 0.0  # > 0: sessions publish live frames (benchmark.running.live_channel)
    # link faults for every session (emulator.link_faults.LinkFaults.to_json()), else each
    # session file's own ``link_faults``, if any
    link_faults: dict[str, Any] | None = None
    # a hung agent (no tool call, no simulated time) is stopped after this many wall seconds
    agent_timeout_s: float = 600.0
    # where a plug-in's relative file path is found (default: this process's directory)
    agent_base_dir: str = ""
    external_host: str = "127.0.0.1"  # --agent external: where each session's server listens

    @property
    def results_path(self) -> Path:
        return self.out_dir / "results.jsonl"


@dataclass
class RunOutcome:
    records_written: int = 0
    skipped: int = 0
    errors: list[str] = field(default_factory=list)
    wall_s: float = 0.0


def make_agent(name: str, session: Session, plan: RunPlan | None = None, trial: int = 0
               ) -> Agent:
    """The named agent (a built-in or a plug-in, `swarm_agents.plugins`) for one session
    and trial."""
    plan = plan or RunPlan(sessions=())
    options = AgentOptions(agent=name, session_id=session.id, trial=trial, model=plan.model,
                           base_url=plan.base_url,
                           price_in_usd_per_mtok=plan.price_in_usd_per_mtok,
                           price_out_usd_per_mtok=plan.price_out_usd_per_mtok)
    return plugins.make_agent(name, session, options, plan.agent_base_dir)


def _limited(session: Session, limit: int | None) -> Session:
    return session if limit is None else replace(session, tasks=session.tasks[:limit])


def run_unit(plan: RunPlan, unit: Unit, send: Handle) -> None:
    """Run one session file for one trial, skipping the tasks `unit.done` holds; each message
    is sent as it happens. Every backend calls this (or `run_unit_async` in a process that
    hosts several sessions at once), on whatever machine runs the unit."""
    asyncio.run(run_unit_async(plan, unit, send))


async def run_unit_async(plan: RunPlan, unit: Unit, send: Handle) -> None:
    """`run_unit` in the running event loop, beside other sessions the loop may host."""
    path, trial, done = unit.path, unit.trial, unit.done
    set_mavsdk_log(plan.mavsdk_log)
    try:
        loaded, notes = load_any_session(path)
        session = _limited(loaded, plan.task_limit)
    except SessionFileError as error:
        records = _unloadable_records(path, plan, trial, str(error), done)
        for record in records:
            send(("record", record))
        if not records:
            send(("error", str(error)))
        return
    if trial == 0:
        for note in notes_to_show(notes):
            send(("note", f"{path}: {note}"))
    if not session.tasks:
        send(("note", f"{path}: the session has no tasks; nothing to run"))
    options = EpisodeOptions(trial=trial, physics_hz=plan.physics_hz, clock=plan.clock,
                             link_faults=plan.link_faults,
                             agent_wall_timeout_s=plan.agent_timeout_s)
    if plan.agent == EXTERNAL:  # a hosted run: the agent is outside (benchmark/running/hosted)
        from benchmark.running.hosted.agent import UNBOUNDED_WALL_S, ExternalAgent
        agent: Agent = ExternalAgent(session, send, trial=trial, host=plan.external_host)
        options = replace(options, agent_wall_timeout_s=UNBOUNDED_WALL_S)
    else:
        agent = make_agent(plan.agent, session, plan, trial)
    world = _world_of(path)

    def emit(record: dict[str, Any]) -> None:
        nonlocal world
        if world is not None and "replay" in record:
            record["replay_world"], world = world, None  # once per unit: the driver keeps it
        send(("record", record))

    live = None
    if plan.live_hz > 0:
        live = LiveChannel(lambda payload: send(("live", payload)), plan.live_hz)
    try:
        await _in_agent_context(agent, run_session(session, agent, emit=emit, done=done,
                                                   options=options, live=live))
    except Exception as error:  # the swarm or gateway failed: report, keep the run going
        send(("error", f"{path} (trial {trial}): {type(error).__name__}: {error}"))


@dataclass(frozen=True)
class PlanWork:
    """A plan's unit work, as backends call it: `run_unit` (a process or Ray task per unit)
    or `hosted` (`run_unit_async`, several units side by side in one process's loop)."""

    plan: RunPlan

    def __call__(self, unit: Unit, send: Handle) -> None:
        run_unit(self.plan, unit, send)

    async def hosted(self, unit: Unit, send: Handle) -> None:
        await run_unit_async(self.plan, unit, send)


async def _in_agent_context(agent: Agent, work: Awaitable[None]) -> None:
    """Run `work`, inside `agent` when it is an async context manager (what it serves or
    holds for the whole session: a hosted agent's server)."""
    if isinstance(agent, contextlib.AbstractAsyncContextManager):
        async with agent:
            await work
    else:
        await work


def _world_of(path: str) -> dict[str, Any] | None:
    """The session file's world (drones, targets, obstacles) for replays; None if unreadable."""
    try:
        data = read_session_json(path)
    except SessionFileError:
        return None
    return session_world(data) if isinstance(data, dict) else None


def _keep_replay(out_dir: Path, record: dict[str, Any],
                 progress: Callable[[str], None]) -> None:
    """Store a record's replay data apart from results.jsonl (the record keeps none)."""
    replay, world = record.pop("replay", None), record.pop("replay_world", None)
    if replay is None:
        return
    try:
        write_task_replay(out_dir, record, replay, world)
    except (OSError, ValueError) as error:  # a replay lost never loses the result
        progress(f"note: replay of {record['key']} not stored: {error}")


def _unloadable_records(path: str, plan: RunPlan, trial: int, error: str,
                        done: Mapping[str, Any]) -> list[dict[str, Any]]:
    """task_error records for the tasks a session file lists when the session itself cannot
    be loaded (so reports count them as failed); none when not even its tasks can be read."""
    try:
        data = read_session_json(path)
    except SessionFileError:
        return []
    if not isinstance(data, dict) or not isinstance(data.get("id"), str):
        return []
    tasks = [t for t in data.get("tasks") or [] if isinstance(t, dict)
             and isinstance(t.get("id"), str)][:plan.task_limit]
    bases = [base_record(session_id=data["id"], family=str(data.get("family", "")),
                         level=str(data.get("level", "")), task_id=task["id"],
                         template=str(task.get("template", "")),
                         category=str(task.get("category", "")), agent=plan.agent, trial=trial)
             for task in tasks]
    return [error_record(base, f"the session cannot be loaded: {error}")
            for base in bases if base["key"] not in done]


def _done_by_unit(records: Sequence[Mapping[str, Any]]
                  ) -> dict[tuple[str, int], dict[str, Any]]:
    """Recorded end states, grouped by (session id, trial): each unit gets only its own."""
    done: dict[tuple[str, int], dict[str, Any]] = {}
    for r in records:
        if "key" in r:
            unit = (str(r.get("session")), int(r.get("trial", 0)))
            done.setdefault(unit, {})[r["key"]] = r.get("end_state")
    return done


def check_session_files(paths: Sequence[Path]) -> None:
    """Refuse, before anything runs, a session file that cannot be read as a JSON object or
    that lists no tasks (nothing to run); SessionFileError naming the file."""
    for path in paths:
        data = read_session_json(path)
        if not isinstance(data, dict):
            raise SessionFileError(f"{path}: the top level must be a JSON object")
        if not data.get("tasks"):
            raise SessionFileError(f"{path}: the session has no tasks, so there is nothing to "
                                   "run (add tasks in the console's editor, or fly it with "
                                   "`mavswarm up --session`)")


def _known_tasks(paths: Sequence[Path]) -> dict[str, frozenset[str]] | None:
    """The sessions' ids and task ids, as their records name them (a session that cannot be
    loaded: as its file lists them); None when a file lists none (its records cannot be told
    from damaged ones)."""
    known: dict[str, frozenset[str]] = {}
    for path in paths:
        try:
            session, _ = load_any_session(path)
            known[session.id] = frozenset(t.id for t in session.tasks)
            continue
        except SessionFileError:
            pass
        try:
            data = read_session_json(path)
        except SessionFileError:
            return None
        if not isinstance(data, dict) or not isinstance(data.get("id"), str):
            return None
        known[data["id"]] = frozenset(t["id"] for t in data.get("tasks") or []
                                      if isinstance(t, dict) and isinstance(t.get("id"), str))
    return known


def run_benchmark(plan: RunPlan, progress: Callable[[str], None] = print, *,
                  sink: ProgressSink | None = None,
                  on_record: Callable[[dict[str, Any]], None] | None = None,
                  on_live: Callable[[dict[str, Any]], None] | None = None,
                  on_message: Handle | None = None) -> RunOutcome:
    """Run the plan; returns what was written. Results go to plan.results_path. Each task's
    line and every note or error go to `sink` (default: lines handed to `progress`);
    `on_record` hears each record right after it was appended (e.g. the MQTT bus). With
    `plan.live_hz`, each live frame a session publishes is handed to `on_live`; messages of
    other kinds (a hosted run's ``("hosted", ...)``) go to `on_message`."""
    if not plan.agent_base_dir:
        plan = replace(plan, agent_base_dir=os.getcwd())
    if plan.agent != EXTERNAL:  # one line, before anything runs
        plugins.check_spec(plan.agent, plan.agent_base_dir)
    if not plan.agent_timeout_s > 0:
        raise ValueError(f"the agent timeout must be > 0 s, got {plan.agent_timeout_s:g}")
    if plan.agent in LLM_AGENTS:
        from swarm_agents.llm import ModelConfig
        ModelConfig(base_url=plan.base_url, model=plan.model).resolved()  # fail fast
    workers = plan.workers
    if workers == AUTO:
        workers = auto_workers(plan.agent, plan.trials * len(plan.sessions))
    if not isinstance(workers, int) or workers < 1 or plan.trials < 1:
        raise ValueError(f"workers must be >= 1 or {AUTO!r}, trials >= 1 (got "
                         f"{plan.workers!r}, {plan.trials!r})")
    out = sink if sink is not None else LineProgress(progress)
    backend = make_backend(plan.backend, workers=workers, ray_address=plan.ray_address,
                           shared=shares_processes(plan.agent))
    started = time.perf_counter()
    outcome = RunOutcome()
    log = ResultsLog(plan.results_path)
    keys = log.open()
    if log.repaired:
        out.say(f"repaired {log.repaired} torn line(s) at the end of {plan.results_path}")
    try:  # resume: every record read back must be one of this run's tasks
        previous = (read_task_records(plan.results_path, _known_tasks(plan.sessions))
                    if keys else [])
    except BaseException:
        log.close()
        raise
    done = _done_by_unit(previous)
    heads = session_heads(plan.sessions)
    order = run_order(plan.sessions, heads, plan.agent) if workers > 1 else plan.sessions
    units = [Unit(str(p), trial, done.get((heads[p].id or "", trial), {}))
             for trial in range(plan.trials) for p in order]
    limit = plan.task_limit
    planned = plan.trials * sum(heads[p].tasks if limit is None else min(heads[p].tasks, limit)
                                for p in plan.sessions)
    passed = {r["key"]: r.get("passed") is True for r in previous}
    already = [key for unit in units for key in unit.done]
    out.begin(planned, len(already), sum(passed.get(key, False) for key in already))

    def handle(message: tuple[str, Any]) -> None:
        kind, payload = message
        if kind == "record":
            if payload["key"] in log:
                return
            _keep_replay(plan.out_dir, payload, progress)
            log.append(payload)
            outcome.records_written += 1
            if on_record is not None:
                on_record(payload)
            out.advance(task_line(payload, outcome.records_written), payload["passed"])
        elif kind == "error":
            outcome.errors.append(payload)
            out.say(f"error: {payload}")
        elif kind == "note":
            out.say(f"note: {payload}")
        elif kind == "live" and on_live is not None:
            on_live(payload)
        elif kind != "live" and on_message is not None:
            on_message(message)

    try:
        backend.run(PlanWork(plan), units, handle)
    finally:
        log.close()
    outcome.wall_s = time.perf_counter() - started
    return outcome
