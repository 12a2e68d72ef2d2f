"""Proving tasks with the oracle, as the shipped suite is proved: the oracle flies each task
(its hand plan where it has one, else a plan derived from the checks) through the agent tools
on the session's swarm, the tasks in order as a run takes them, and the checks judge it.

A task that is not proved is named with the leaf that stopped it and why: the leaf the planner
could not plan (and its reason), or the first leaf that failed (what it measured against what
it required), or the task's own error.
"""

from __future__ import annotations

import asyncio
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from agent_contract import Agent
from benchmark.authoring.generate import ORACLE_TRIES
from benchmark.authoring.importer import import_session_file
from benchmark.authoring.session_file import Session, TaskSpec
from benchmark.running.episode import EpisodeOptions, run_task, session_swarm
from benchmark.scoring.failed_checks import failed_leaves
from emulator.services import SwarmServices
from emulator.swarm import Swarm
from mavlink_gateway import Gateway
from swarm_agents.oracle import oracle_for_session

__all__ = ["TaskProof", "fly_task", "import_files", "proof_of", "prove_session"]

_CANNOT_PLAN = re.compile(r"cannot plan (\S+) \(([^)]*)\): (.*)$", re.DOTALL)


@dataclass(frozen=True)
class TaskProof:
    """Whether the oracle passed one task; if not, the leaf and the reason."""

    session: str
    task: str
    template: str
    proved: bool
    leaf: str = ""
    endpoint: str = ""
    reason: str = ""

    def line(self) -> str:
        """One line for a reader."""
        if self.proved:
            return f"{self.session} {self.task} ({self.template}): proved"
        where = f"{self.leaf} {self.endpoint}".strip() or "task"
        return (f"{self.session} {self.task} ({self.template}): NOT proved: {where}: "
                f"{self.reason}")

    def to_json(self) -> dict[str, Any]:
        """The task's ``proof`` field in a session file."""
        out = {k: v for k, v in asdict(self).items()
               if k in ("proved", "leaf", "endpoint", "reason") and v != ""}
        return {"by": "oracle", **out}


def proof_of(session_id: str, task: TaskSpec, record: Mapping[str, Any]) -> TaskProof:
    """The proof a task's oracle record gives."""
    base = {"session": session_id, "task": task.id, "template": task.template}
    if record.get("passed"):
        return TaskProof(**base, proved=True)
    error = str(record.get("error") or "")
    planned = _CANNOT_PLAN.search(error)
    if planned is not None:
        return TaskProof(**base, proved=False, leaf=planned.group(1),
                         endpoint=planned.group(2), reason=f"no plan: {planned.group(3)}")
    failed = failed_leaves(record)
    ending = "" if record.get("finish") in (None, "finished") else (
        f" (the oracle's flight ended: {record.get('finish')}{f': {error}' if error else ''})")
    if not failed:
        return TaskProof(**base, proved=False, reason=(error or "not passed") + ending)
    leaf = failed[0]
    measured = f"measured {leaf.measured}" + (f" against {leaf.threshold}"
                                              if leaf.threshold else "")
    about = f" ({leaf.subject})" if leaf.subject else ""
    note = f"; {leaf.note}" if leaf.note else ""
    more = f"; {len(failed) - 1} more leaves failed" if len(failed) > 1 else ""
    return TaskProof(**base, proved=False, leaf=leaf.path, endpoint=leaf.endpoint,
                     reason=f"failed{about}: {measured}{note}{more}{ending}")


async def fly_task(session: Session, spec: TaskSpec, agent: Agent, swarm: Swarm,
                   services: SwarmServices, gateway: Gateway, start: dict[str, Any]
                   ) -> dict[str, Any]:
    """Fly a task with the oracle, up to ORACLE_TRIES times from the same start: a task is
    kept if the oracle can pass it, so a rare slow telemetry hiccup is not a verdict. After a
    failure the drones are put back where the task started. The last flight's record."""
    record: dict[str, Any] = {}
    for _ in range(ORACLE_TRIES):
        record = await run_task(session, spec, agent, swarm, services, gateway,
                                EpisodeOptions())
        if record["passed"]:
            return record
        services.operator_restore(start)
    return record


def _task_error(session_id: str, task: TaskSpec) -> TaskProof:
    return TaskProof(session_id, task.id, task.template, False, reason=f"the task cannot be "
                     f"run: {task.error or 'no checks or budget'}")


async def _prove_all(session: Session, progress: Callable[[TaskProof], None]
                     ) -> list[TaskProof]:
    agent = oracle_for_session(session, "hand")  # hand plans, else derived from the checks
    proofs: list[TaskProof] = []
    async with session_swarm(session, EpisodeOptions()) as (swarm, services, gateway):
        for task in session.tasks:
            if task.error is not None or task.checks is None or task.budget is None:
                proofs.append(_task_error(session.id, task))
                progress(proofs[-1])
                continue
            record = await fly_task(session, task, agent, swarm, services, gateway,
                                    services.operator_snapshot())
            proofs.append(proof_of(session.id, task, record))
            progress(proofs[-1])
    return proofs


def prove_session(session: Session, *, progress: Callable[[TaskProof], None] = lambda p: None
                  ) -> list[TaskProof]:
    """Fly every task of a session with the oracle, in order; one proof per task."""
    return asyncio.run(_prove_all(session, progress))


def import_files(paths: Sequence[Path], out_dir: Path, *, prove: bool = True,
                 echo: Callable[[str], None] = print) -> int:
    """`bench import`: convert (and prove) each file, telling `echo` what was written, the
    notes, and every task not proved with its leaf and reason; the number not proved."""
    taken: set[str] = set()
    unproved = 0
    for path in paths:
        proofs: list[TaskProof] = []

        def flown(session: Session, proofs: list[TaskProof] = proofs
                  ) -> list[dict[str, Any]]:
            return [p.to_json() for p in prove_session(session, progress=proofs.append)]

        written, notes = import_session_file(path, out_dir, taken=taken,
                                             prove=flown if prove else None)
        echo(f"{path} -> {written}")
        for note in notes:
            echo(f"  note: {note}")
        if not prove:
            continue
        failed = [p for p in proofs if not p.proved]
        unproved += len(failed)
        for proof in failed:
            echo(f"  {proof.line()}")
        echo(f"  oracle: {len(proofs) - len(failed)} of {len(proofs)} tasks proved")
    return unproved
