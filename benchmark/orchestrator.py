"""Runs an agent over benchmark sessions into a resumable JSON Lines results file.

Each (session, trial) is one unit of work, run by `run_unit` with its own swarm and ports,
wherever the backend puts it (`benchmark/backends.py`: this process, local worker processes,
or Ray tasks on a cluster). Units send each task's record back as the task ends; this process
alone appends to the results file, one whole line at a time, and never a key twice.
Re-running the same command skips every task already recorded and restores the layout the
last one left.
"""

from __future__ import annotations

import asyncio
import functools
import json
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from agent_contract import Agent
from benchmark.agents import NoopAgent
from benchmark.backends import Handle, Unit, make_backend
from benchmark.episode import EpisodeOptions, base_record, error_record, run_session
from benchmark.importer import load_any_session
from benchmark.results import ResultsLog, read_records
from benchmark.session_file import Session, SessionFileError, read_session_json
from emulator.reference_mapping import notes_to_show

__all__ = ["AGENTS", "RunOutcome", "RunPlan", "make_agent", "run_benchmark", "run_unit"]

# NAME:per-drone: one instance of NAME per drone (agent_contract.per_drone)
AGENTS = ("oracle", "noop", "react", "workflow", "react:per-drone", "workflow:per-drone")
LLM_AGENTS = ("react", "workflow", "react:per-drone", "workflow:per-drone")
PER_DRONE = ":per-drone"


@dataclass(frozen=True)
class RunPlan:
    sessions: tuple[Path, ...]
    agent: str = "oracle"
    trials: int = 1
    workers: int = 1
    out_dir: Path = Path("runs/bench")
    task_limit: int | None = None  # only the first N tasks of each session (smoke runs)
    physics_hz: float = 50.0
    clock: str = "lockstep"  # see benchmark.episode.CLOCKS
    model: str = ""  # LLM agents: model name and OpenAI-compatible base URL (else from the
    base_url: str = ""  # environment: OPENAI_MODEL, OPENAI_BASE_URL; key: OPENAI_API_KEY)
    price_in_usd_per_mtok: float = 0.0  # token prices for the cost per task (else from
    price_out_usd_per_mtok: float = 0.0  # MAVSWARM_PRICE_IN / MAVSWARM_PRICE_OUT)
    backend: str = "local"  # where units run: "local" (processes here) or "ray" (a cluster)
    ray_address: str = ""  # the Ray cluster to join (else Ray's own rules; see ray_backend)
    # link faults for every session (emulator.link_faults.LinkFaults.to_json()), else each
    # session file's own ``link_faults``, if any
    link_faults: dict[str, Any] | None = None

    @property
    def results_path(self) -> Path:
        return self.out_dir / "results.jsonl"


@dataclass
class RunOutcome:
    records_written: int = 0
    skipped: int = 0
    errors: list[str] = field(default_factory=list)
    wall_s: float = 0.0


def make_agent(name: str, session: Session, plan: RunPlan | None = None) -> Agent:
    """The named agent for one session."""
    if name.endswith(PER_DRONE):
        from agent_contract.per_drone import PerDroneTeam
        single = name.removesuffix(PER_DRONE)
        return PerDroneTeam(name, lambda drone_id: make_agent(single, session, plan))
    if name == "noop":
        return NoopAgent()
    if name in LLM_AGENTS:
        from llm_tools.agents import ModelConfig, ReactAgent, WorkflowAgent
        plan = plan or RunPlan(sessions=())
        config = ModelConfig(base_url=plan.base_url, model=plan.model,
                             price_in_usd_per_mtok=plan.price_in_usd_per_mtok,
                             price_out_usd_per_mtok=plan.price_out_usd_per_mtok)
        return ReactAgent(config) if name == "react" else WorkflowAgent(config)
    if name == "oracle":
        from benchmark.oracle import OracleAgent
        plans = {t.id: t.oracle for t in session.tasks if t.oracle is not None}
        return OracleAgent(session.scenario, plans)
    raise ValueError(f"unknown agent {name!r}; choose one of {', '.join(AGENTS)}")


def _limited(session: Session, limit: int | None) -> Session:
    return session if limit is None else replace(session, tasks=session.tasks[:limit])


def run_unit(plan: RunPlan, unit: Unit, send: Handle) -> None:
    """Run one session file for one trial, skipping the tasks `unit.done` holds; each message
    is sent as it happens. Every backend calls this, on whatever machine runs the unit."""
    path, trial, done = unit.path, unit.trial, unit.done
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
    agent = make_agent(plan.agent, session, plan)
    options = EpisodeOptions(trial=trial, physics_hz=plan.physics_hz, clock=plan.clock,
                             link_faults=plan.link_faults)
    try:
        asyncio.run(run_session(session, agent, emit=lambda r: send(("record", r)),
                                done=done, options=options))
    except Exception as error:  # the swarm or gateway failed: report, keep the run going
        send(("error", f"{path} (trial {trial}): {type(error).__name__}: {error}"))


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


def _session_id(path: Path) -> str | None:
    """A session file's id without validating it (an unreadable file: None; the worker
    reports the problem)."""
    try:
        ident = json.loads(path.read_text(encoding="utf-8")).get("id")
    except (OSError, ValueError, AttributeError):
        return None
    return ident if isinstance(ident, str) else None


def run_benchmark(plan: RunPlan, progress: Callable[[str], None] = print) -> RunOutcome:
    """Run the plan; returns what was written. Results go to plan.results_path."""
    if plan.agent not in AGENTS:
        raise ValueError(f"unknown agent {plan.agent!r}; choose one of {', '.join(AGENTS)}")
    if plan.agent in LLM_AGENTS:
        from llm_tools.agents import ModelConfig
        ModelConfig(base_url=plan.base_url, model=plan.model).resolved()  # fail fast
    if plan.workers < 1 or plan.trials < 1:
        raise ValueError("workers and trials must be >= 1")
    backend = make_backend(plan.backend, workers=plan.workers, ray_address=plan.ray_address)
    started = time.perf_counter()
    outcome = RunOutcome()
    log = ResultsLog(plan.results_path)
    keys = log.open()
    if log.repaired:
        progress(f"repaired {log.repaired} torn line(s) at the end of {plan.results_path}")
    done = _done_by_unit(read_records(plan.results_path)) if keys else {}
    ids = {p: _session_id(p) for p in plan.sessions} if done else {}
    units = [Unit(str(p), trial, done.get((ids.get(p) or "", trial), {}))
             for trial in range(plan.trials) for p in plan.sessions]

    def handle(message: tuple[str, Any]) -> None:
        kind, payload = message
        if kind == "record":
            if payload["key"] in log:
                return
            log.append(payload)
            outcome.records_written += 1
            progress(_progress_line(payload, outcome.records_written))
        elif kind == "error":
            outcome.errors.append(payload)
            progress(f"error: {payload}")
        elif kind == "note":
            progress(f"note: {payload}")

    try:
        backend.run(functools.partial(run_unit, plan), units, handle)
    finally:
        log.close()
    outcome.wall_s = time.perf_counter() - started
    return outcome


def _progress_line(record: Mapping[str, Any], n: int) -> str:
    verdict = "PASS" if record["passed"] else "fail"
    extra = f"  [{record['finish']}]" if record["finish"] != "finished" else ""
    return (f"{n:5d} {record['session']:<38} {record['task']:<4} {record['template']:<28} "
            f"{verdict} {record['checks_passed']:>2}/{record['checks_total']:<2} checks "
            f"{record['tool_calls']:>3} calls {record['sim_time_s']:>7.0f} s sim "
            f"{record['wall_time_s']:>6.2f} s{extra}")
