"""Proving one task of the session being edited, from the editor's page: the oracle flies it
on a sandbox swarm of its own (127.0.0.1, the session's starting layout, the clock and options
of a benchmark run), which the console shows as a live swarm (`proof-N`: its frames over the
live WebSocket) while it flies; the proof's record then carries the checks' verdicts and the
replay of the window, which the page plays back.

As generation proves a task, the oracle gets `ORACLE_TRIES` flights from the same start (a rare
telemetry hiccup does not fail a task the suite would keep); the proof says how many it took.
One proof runs at a time per console (a second is refused while one flies); the last
`KEEP_PROOFS` are kept to be read back. Nothing of a proof reaches any other swarm, session or
results folder.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from benchmark.authoring.generate import ORACLE_TRIES
from benchmark.authoring.session_file import Session, TaskSpec, session_from_dict
from benchmark.running.episode import EpisodeOptions, run_task, session_swarm
from console.editor import EditorError, validate_session
from console.live import LiveSwarm
from emulator.scenario_export import scenario_to_dict
from swarm_agents.oracle.session_oracle import oracle_for_session

__all__ = ["KEEP_PROOFS", "Proof", "ProofBusy", "ProofRunner"]

KEEP_PROOFS = 8
log = logging.getLogger("mavswarm.console")


class ProofBusy(RuntimeError):
    """A proof is already flying."""


@dataclass
class Proof:
    """One proof: `status` running, passed, failed or error (the task could not be flown)."""

    id: str
    task_id: str
    status: str = "running"
    record: dict[str, Any] | None = None
    error: str | None = None
    last_frame: dict[str, Any] | None = None
    tries: int = 0
    task: asyncio.Task[None] | None = field(default=None, repr=False)

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"id": self.id, "task": self.task_id, "status": self.status,
                               "error": self.error, "live": self.id, "tries": self.tries}
        if self.record is not None:
            keep = ("passed", "checks", "checks_total", "checks_passed", "finish", "error",
                    "tool_calls", "sim_time_s", "replay")
            out["record"] = {k: self.record.get(k) for k in keep}
        return out


class ProofRunner:
    """Runs the editor's proofs; `lives`: the console's live swarms (a proof joins them while
    it flies); `forget_feed(id)`: drops a finished proof's frame feed."""

    def __init__(self, lives: dict[str, LiveSwarm],
                 forget_feed: Callable[[str], Any] | None = None) -> None:
        self.lives = lives
        self.forget_feed = forget_feed
        self.proofs: dict[str, Proof] = {}
        self._numbers = itertools.count(1)

    def running(self) -> Proof | None:
        return next((p for p in self.proofs.values() if p.status == "running"), None)

    def _check_idle(self) -> None:
        busy = self.running()
        if busy is not None:
            raise ProofBusy(f"proof {busy.id} of task {busy.task_id} is flying; wait for it")

    def prepare(self, data: Any, task_id: str) -> tuple[Session, TaskSpec]:
        """The session (its world and task `task_id` alone) a proof flies; raises EditorError
        for a session or task that cannot be flown, ProofBusy. Any thread may call it."""
        self._check_idle()
        if not isinstance(data, dict):
            raise EditorError("the session must be a JSON object")
        listed = [t for t in data.get("tasks") or [] if isinstance(t, dict)]
        tasks = [t for t in listed if t.get("id") == task_id]
        if not tasks:
            known = ", ".join(str(t.get("id"))[:64] for t in listed[:20]) or "none"
            raise EditorError(f"no task {task_id[:64]!r} in the session; tasks: {known}")
        validate_session({**data, "tasks": tasks[:1]})  # the world, and this task alone
        session = session_from_dict({**data, "tasks": tasks[:1]}, source=str(data.get("id")))
        spec = session.tasks[0]
        if spec.error is not None or spec.checks is None or spec.budget is None:
            raise EditorError(f"tasks[0] ({task_id}): {spec.error or 'no checks or budget'}")
        return session, spec

    def start(self, session: Session, spec: TaskSpec) -> Proof:
        """Start flying a prepared proof (call from the server's loop); raises ProofBusy."""
        self._check_idle()
        task_id = spec.id
        ident = f"proof-{next(self._numbers)}"
        while ident in self.lives:  # never in place of a swarm the console shows
            ident = f"proof-{next(self._numbers)}"
        proof = Proof(ident, task_id)
        self.proofs[proof.id] = proof
        self._evict()
        agent = oracle_for_session(session, "hand")

        async def fly() -> None:
            options = EpisodeOptions()
            try:
                async with session_swarm(session, options) as (swarm, services, gateway):
                    live = LiveSwarm(proof.id, f"proof of {task_id} ({session.name})",
                                     scenario_to_dict(session.scenario), swarm,
                                     task_text=spec.text)
                    self.lives[proof.id] = live
                    start = services.operator_snapshot()
                    try:
                        for attempt in range(1, ORACLE_TRIES + 1):  # as generation proves
                            if attempt > 1:
                                services.operator_restore(start)
                            proof.tries = attempt
                            record = await run_task(session, spec, agent, swarm, services,
                                                    gateway, options)
                            if record["passed"]:
                                break
                    finally:  # the page keeps the last frame; the swarm goes, and the
                        proof.last_frame = live.state()  # live entry once the end is read
                        live.swarm, live.frames = None, lambda: proof.last_frame
                proof.record = record
                proof.status = "passed" if record["passed"] else "failed"
                proof.error = record.get("error")
            except asyncio.CancelledError:
                proof.status, proof.error = "error", "the console stopped"
                raise
            except Exception as error:  # a proof that cannot fly is answered, never raised
                log.exception("proof %s failed", proof.id)
                proof.status, proof.error = "error", f"{type(error).__name__}: {error}"

        proof.task = asyncio.get_running_loop().create_task(fly(), name=proof.id)
        return proof

    def seen(self, ident: str) -> Proof | None:
        """The proof `ident` as a page reads it; a finished proof's live swarm (its last
        frame) is listed until then, so that even a flight quicker than a page's poll is seen
        live once."""
        proof = self.proofs.get(ident)
        if proof is not None and proof.status != "running":
            self.lives.pop(proof.id, None)
        return proof

    def _evict(self) -> None:
        for ident in list(self.proofs)[:-KEEP_PROOFS]:
            if self.proofs[ident].status != "running":
                self.proofs.pop(ident)
                self.lives.pop(ident, None)
                if self.forget_feed is not None:
                    self.forget_feed(ident)

    async def aclose(self) -> None:
        for proof in self.proofs.values():
            if proof.task is not None and not proof.task.done():
                proof.task.cancel()
                with contextlib.suppress(asyncio.CancelledError, Exception):
                    await proof.task
