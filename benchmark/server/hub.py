"""What the REST API serves: live sessions, and the API keys that may reach them."""

from __future__ import annotations

import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

from agent_contract import AgentTools
from benchmark.authoring.session_file import Session, TaskSpec
from benchmark.authoring.session_folders import SessionFolders
from emulator.services import SwarmServices
from emulator.swarm import Swarm
from mavlink_gateway import Gateway

__all__ = ["Caller", "Hub", "LiveSession", "Role"]


class Role(StrEnum):
    AGENT = "agent"  # its own session's drones, their perception, its task text
    OPERATOR = "operator"  # every session's live views, no hidden checks
    ADMIN = "admin"  # everything, including hidden checks


@dataclass(frozen=True)
class Caller:
    """Who made a request: the role of the key, and for an agent the session it is bound to."""

    role: Role
    session_id: str | None = None
    drone_id: str | None = None  # an agent key of one drone's agent (per-drone agents)


@dataclass
class LiveSession:
    """One running session: its swarm and gateway, the current task and the agent's tools.

    `task_start_s` is the simulated time the current task began (the start of the window the
    hidden checks look at).
    """

    session: Session
    task: TaskSpec
    swarm: Swarm
    services: SwarmServices
    gateway: Gateway
    tools: AgentTools
    task_start_s: float
    started_wall_s: float = field(default_factory=time.time)  # the compat routes' created_at
    task_marks: dict[str, dict[str, bool]] = field(default_factory=dict)
    """The reference's `is_done` / `is_passed` per task id, as its routes set them."""
    environments: dict[str, dict[str, Any]] = field(default_factory=dict)
    """The reference's environment records by id (compat_environments); empty until used."""

    @property
    def id(self) -> str:
        return self.session.id


class Hub:
    """Live sessions by id and API keys by value."""

    def __init__(self, *, open_access: bool = False) -> None:
        self.sessions: dict[str, LiveSession] = {}
        self._keys: dict[str, Caller] = {}
        self.open_access = open_access
        """Requests without a key act as the agent of the current session (MultiUAV-Plat
        clients send no key); off unless the server was started with --open."""
        self.current_id: str | None = None
        """The session an operator made current (by loading it or picking it); see
        `current`."""
        self.starter: Callable[[Session], Awaitable[LiveSession]] | None = None
        """Starts a live session (swarm and gateway) for a loaded session file; None where
        the server cannot load sessions while it runs."""
        self.stopper: Callable[[str], Awaitable[None]] | None = None
        """Closes a live session's swarm and gateway (`DELETE /sessions/{id}`); None where the
        server cannot stop sessions while it runs."""
        self.session_folders = SessionFolders()
        """Where `POST /sessions/load {"path": ...}` reads files
        (benchmark.authoring.session_folders)."""

    def add_session(self, live: LiveSession) -> None:
        if live.id in self.sessions:
            raise ValueError(f"session id {live.id!r} is already in the hub")
        self.sessions[live.id] = live

    def current(self) -> str | None:
        """The current session: the one an operator made current, else the only one served;
        None when several are served and none was picked."""
        if self.current_id in self.sessions:
            return self.current_id
        return next(iter(self.sessions)) if len(self.sessions) == 1 else None

    def add_key(self, key: str, role: Role | str, session_id: str | None = None,
                drone_id: str | None = None) -> None:
        """Register an API key. An agent key must name a session in the hub (and may name one
        of its drones: that drone's agent); other roles must not name one."""
        if not isinstance(key, str) or not key.strip():
            raise ValueError(f"key: expected a non-empty string, got {key!r}")
        try:
            role = Role(role)
        except ValueError:
            raise ValueError(f"role: expected one of {[r.value for r in Role]}, "
                             f"got {role!r}") from None
        if role is Role.AGENT:
            if session_id not in self.sessions:
                raise ValueError(f"session_id: an agent key needs a session of the hub "
                                 f"({', '.join(self.sessions) or 'none'}), got {session_id!r}")
        elif session_id is not None:
            raise ValueError(f"session_id: only agent keys are bound to a session, got "
                             f"{session_id!r} for role {role.value!r}")
        if drone_id is not None and (role is not Role.AGENT or drone_id
                                     not in self.sessions[str(session_id)].gateway.drones):
            raise ValueError(f"drone_id: {drone_id!r} is not a drone of session {session_id!r}"
                             if role is Role.AGENT else "drone_id: only agent keys name a drone")
        if key in self._keys:
            raise ValueError("key: this API key is already registered")
        self._keys[key] = Caller(role, session_id, drone_id)

    def caller(self, key: str) -> Caller | None:
        return self._keys.get(key)

    def keyless_caller(self) -> Caller | None:
        """Who a request without a key is: the agent of the current session when the hub is
        open, else nobody."""
        current = self.current()
        if not self.open_access or current is None:
            return None
        return Caller(Role.AGENT, current)
