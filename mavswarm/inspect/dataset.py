"""Benchmark sessions as inspect samples: one sample per task, identified as
``<session>/<task>``, whose input is the message that opens the task for the agent.

Sessions are named by id (a session of the shipped suite, e.g. ``area_search-easy-1``) or by
path (a mavswarm session file, or a MultiUAV-Plat file read as ``bench import`` reads it).
Sample metadata says where the task comes from (session file, family, level, template,
category); the checks, the oracle and the world's truth stay out of it.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from inspect_ai.dataset import MemoryDataset, Sample

from benchmark.authoring.importer import load_any_session
from benchmark.authoring.scenarios import FAMILIES, LEVELS, all_session_keys, session_id
from benchmark.authoring.session_file import Session, SessionFileError
from benchmark.authoring.suite import SESSIONS_DIR
from swarm_agents.llm.react import task_message

__all__ = ["family_paths", "load_session", "session_dataset", "session_paths"]


def session_paths(sessions: str | Sequence[str]) -> tuple[Path, ...]:
    """Session files from ids of the shipped suite or paths (a list, or one comma-separated
    string); ValueError naming what was not found."""
    names = sessions.split(",") if isinstance(sessions, str) else list(sessions)
    names = [str(n).strip() for n in names if str(n).strip()]
    if not names:
        raise ValueError("sessions: name at least one session id or session file")
    paths, missing = [], []
    for name in names:
        shipped = SESSIONS_DIR / f"{name}.json"
        path = Path(name)
        if path.suffix == "" and shipped.is_file():
            paths.append(shipped)
        elif path.is_file():
            paths.append(path)
        else:
            missing.append(name)
    if missing:
        raise ValueError(f"sessions: no session id or file {', '.join(map(repr, missing))} "
                         f"(ids look like {session_id(*next(iter(all_session_keys())))}; "
                         f"the shipped ones are in {SESSIONS_DIR})")
    return tuple(paths)


def family_paths(family: str, level: str | Sequence[str] | None = None) -> tuple[Path, ...]:
    """The shipped sessions of one family, at every level or the ones named."""
    if family not in FAMILIES:
        raise ValueError(f"unknown family {family!r}; choose one of {', '.join(FAMILIES)}")
    levels = LEVELS if level is None else (
        level.split(",") if isinstance(level, str) else list(level))
    levels = [str(x).strip() for x in levels]
    unknown = [x for x in levels if x not in LEVELS]
    if unknown:
        raise ValueError(f"unknown level(s) {', '.join(map(repr, unknown))}; choose from "
                         f"{', '.join(LEVELS)}")
    return session_paths([session_id(f, lv, i) for f, lv, i in all_session_keys()
                          if f == family and lv in levels])


def load_session(path: str | Path) -> Session:
    """A session file as a run reads it; ValueError naming the file and the problem."""
    try:
        session, _ = load_any_session(path)
    except SessionFileError as error:
        raise ValueError(str(error)) from None
    return session


def session_dataset(paths: Sequence[Path], task_limit: int | None = None, *,
                    name: str = "mavswarm") -> MemoryDataset:
    """One sample per task of each session (the first `task_limit` of each, if given)."""
    if task_limit is not None and task_limit < 1:
        raise ValueError(f"task_limit must be >= 1, got {task_limit}")
    samples: list[Sample] = []
    seen: dict[str, Path] = {}
    for path in paths:
        session = load_session(path)
        if session.id in seen:
            raise ValueError(f"two session files hold session {session.id!r}: {seen[session.id]} "
                             f"and {path}")
        seen[session.id] = path
        drones = [v.id for v in session.scenario.vehicles]
        for task in session.tasks[:task_limit]:
            samples.append(Sample(
                id=f"{session.id}/{task.id}", input=task_message(task.text, drones),
                metadata={"session": session.id, "session_path": str(path),
                          "task": task.id, "family": session.family,
                          "level": session.level, "template": task.template,
                          "category": task.category}))
    return MemoryDataset(samples, name=name)
