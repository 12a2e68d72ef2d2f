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
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass
from typing import Any

from benchmark.episode import EpisodeOptions, run_task, swarm_gateway
from benchmark.failed_checks import failed_leaves
from benchmark.oracle import OracleAgent
from benchmark.session_file import Session, TaskSpec

__all__ = ["ORACLE_TRIES", "TaskProof", "proof_of", "prove_session"]

ORACLE_TRIES = 2
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


def _task_error(session_id: str, task: TaskSpec) -> TaskProof:
    return TaskProof(session_id, task.id, task.template, False, reason=f"the task cannot be "
                     f"run: {task.error or 'no checks or budget'}")


async def _prove_all(session: Session, progress: Callable[[TaskProof], None]
                     ) -> list[TaskProof]:
    agent = OracleAgent(session.scenario, {})
    proofs: list[TaskProof] = []
    async with swarm_gateway(session) as (swarm, services, gateway):
        for task in session.tasks:
            if task.error is not None or task.checks is None or task.budget is None:
                proofs.append(_task_error(session.id, task))
                progress(proofs[-1])
                continue
            agent.set_plan(task.id, task.oracle)
            agent.set_checks(task.id, task.checks, sorted(
                {f.drone for f in task.faults.failures} if task.faults else ()))
            start = services.operator_snapshot()
            record: dict[str, Any] = {}
            for _ in range(ORACLE_TRIES):  # as generation does: a rare hiccup is not a verdict
                record = await run_task(session, task, agent, swarm, services, gateway,
                                        EpisodeOptions())
                if record["passed"]:
                    break
                services.operator_restore(start)
            proofs.append(proof_of(session.id, task, record))
            progress(proofs[-1])
    return proofs


def prove_session(session: Session, *, progress: Callable[[TaskProof], None] = lambda p: None
                  ) -> list[TaskProof]:
    """Fly every task of a session with the oracle, in order; one proof per task."""
    return asyncio.run(_prove_all(session, progress))
