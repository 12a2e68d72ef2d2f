"""Starting and stopping live sessions: a session (a mavswarm or MultiUAV-Plat file, or the same
JSON sent to the server) becomes a stepped swarm, a gateway connected to it over MAVLink, and
the agent's tools for its current task. `mavswarm serve` starts its sessions this way, and an
operator loads more while it runs (`session_loading.py`). The clock is lockstep by default
(`clock="stepped"` for the stepped one): the agent's threads hold it while they think
(`agent_threads.py`)."""

from __future__ import annotations

import contextlib
from collections.abc import Mapping, Sequence
from typing import Any

from agent_contract import AgentTask, AgentTools, TaskBudget
from benchmark.authoring.importer import import_session
from benchmark.authoring.session_file import Session, TaskSpec, session_from_dict
from benchmark.running.episode import CLOCKS, session_link_faults, swarm_gateway
from benchmark.server.agent_threads import ServedTools
from benchmark.server.hub import LiveSession
from benchmark.server.live_faults import start_task_faults
from mavlink_gateway import Gateway

__all__ = ["FREE_FLIGHT", "SessionRunner", "current_task_tools", "first_task",
           "session_from_json", "task_tools"]

FREE_FLIGHT = TaskSpec(
    id="free-flight", template="", category="free flight", difficulty="",
    text="No task is set: the drones are yours to fly.", aliases=(),
    budget=TaskBudget(tool_calls=1_000_000, sim_time_s=30 * 86_400.0), checks=None,
    oracle=None, error="a world without tasks has nothing to check")
"""What a session without tasks serves: free flight, with a budget no one will reach."""


def first_task(session: Session) -> TaskSpec:
    """The session's current task when it starts: its first, or free flight for a world
    without tasks; ValueError when the first task is not usable."""
    if not session.tasks:
        return FREE_FLIGHT
    task = session.tasks[0]
    if task.budget is None:
        raise ValueError(f"{session.source}: task {task.id!r} is not usable: {task.error}")
    return task


def task_tools(gateway: Gateway, session_id: str, task: TaskSpec, *,
               drones: Sequence[str] = ()) -> ServedTools:
    """The agent's tools for `task` under its budget, with its threads (`drones`: one per
    drone, else one for the whole agent); under a lockstep clock a task with checks is held
    while they think, free flight is not. Whoever ends the task (an operator's next task, a
    play-out before the checks) closes them first (`await tools.close()`), or they go on
    holding the clock."""
    assert task.budget is not None
    return ServedTools(gateway, AgentTask(session_id, task.id, task.text, task.budget),
                       pins=gateway.services.lockstep and task.checks is not None,
                       drones=drones)


def current_task_tools(session: Session, gateway: Gateway) -> AgentTools:
    """The agent's tools for the session's current (first) task, under its budget."""
    return task_tools(gateway, session.id, first_task(session))


def session_from_json(data: Any, source: str) -> tuple[Session, list[str]]:
    """A session from parsed JSON, with load_any_session's semantics: a MultiUAV-Plat session
    (no `schema`, a `drones` list) is converted as `bench import` would, with its notes; a
    mavswarm session is read as it is. Raises ValueError (SessionFileError or
    SessionImportError) naming the field."""
    if isinstance(data, Mapping) and data.get("schema") is None and "drones" in data:
        converted, notes = import_session(data, source=source)
        return session_from_dict(converted, source=source), notes
    session = session_from_dict(data, source=source)
    return session, list(session.scenario.notes)


class SessionRunner:
    """Starts live sessions, each with its own swarm and gateway, and closes them all on exit
    (or one by one). Use as an async context manager."""

    def __init__(self, physics_hz: float = 50.0, clock: str = "lockstep") -> None:
        if clock not in CLOCKS:
            raise ValueError(f"clock: expected one of {', '.join(CLOCKS)}, got {clock!r}")
        self.physics_hz = physics_hz
        self.clock = clock
        self._stacks: dict[str, contextlib.AsyncExitStack] = {}

    async def start(self, session: Session) -> LiveSession:
        """Start `session` at its first task, with the session file's link faults and the
        task's hidden faults scheduled from now (live_faults). Nothing is left running when it
        fails: a
        session whose first task is unusable raises ValueError before its swarm starts, and a
        swarm that cannot start (parameters out of range, no port) is closed again."""
        if session.id in self._stacks:
            raise ValueError(f"session {session.id!r} is already running")
        task = first_task(session)
        stack = contextlib.AsyncExitStack()
        try:
            swarm, services, gateway = await stack.enter_async_context(
                swarm_gateway(session, self.physics_hz, lockstep=self.clock == "lockstep",
                              link_faults=session_link_faults(session)))
        except BaseException:
            await stack.aclose()
            raise
        self._stacks[session.id] = stack
        live = LiveSession(session, task, swarm, services, gateway,
                           current_task_tools(session, gateway), services.clock_s())
        start_task_faults(live)
        return live

    async def stop(self, session_id: str) -> None:
        """Close one session's swarm and gateway (nothing when it is not running)."""
        stack = self._stacks.pop(session_id, None)
        if stack is not None:
            await stack.aclose()

    async def aclose(self) -> None:
        """Close every session, the last started first."""
        while self._stacks:
            session_id = next(reversed(self._stacks))
            await self.stop(session_id)

    async def __aenter__(self) -> SessionRunner:
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.aclose()
