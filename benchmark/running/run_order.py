"""The order a benchmark run starts its sessions in, read from the session files before any
is loaded (an unreadable file reads as an empty one; its worker reports the problem)."""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from benchmark.running.worker_count import INSTANT_AGENTS

__all__ = ["SessionHead", "run_order", "session_heads"]


@dataclass(frozen=True)
class SessionHead:
    """What a run needs of a session file before loading it (not validated)."""

    id: str | None  # None: the file has no id (or cannot be read)
    tasks: int
    drones: int
    tool_calls: int  # the tool calls its tasks allow in all (0 where a file does not say)


def session_heads(paths: Sequence[Path]) -> dict[Path, SessionHead]:
    """Each session file's head, every file read once."""
    return {path: _head(_read(path)) for path in paths}


def _read(path: Path) -> dict[str, Any]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _head(data: dict[str, Any]) -> SessionHead:
    ident, tasks, drones = data.get("id"), data.get("tasks"), data.get("drones")
    tasks = tasks if isinstance(tasks, list) else []
    calls = 0
    for task in tasks:
        budget = task.get("budget") if isinstance(task, dict) else None
        allowed = budget.get("tool_calls") if isinstance(budget, dict) else None
        if isinstance(allowed, int) and not isinstance(allowed, bool) and allowed > 0:
            calls += allowed
    return SessionHead(ident if isinstance(ident, str) else None, len(tasks),
                       len(drones) if isinstance(drones, list) else 0, calls)


def run_order(paths: Sequence[Path], heads: Mapping[Path, SessionHead], agent: str
              ) -> list[Path]:
    """The order a run with several workers starts `paths` in (`heads`: theirs, from
    session_heads): the longest first, since
    the run ends when its last session does (results do not depend on the order). An
    agent that answers at once (the oracle, noop) spends a session's time computing, which
    grows with its drones: the largest fleets first. Any other agent spends it thinking
    before each call, one call after another: the sessions whose tasks allow the most tool
    calls in all first (the fleet's size breaks ties)."""
    if agent in INSTANT_AGENTS:
        return sorted(paths, key=lambda p: -heads[p].drones)
    return sorted(paths, key=lambda p: (-heads[p].tool_calls, -heads[p].drones))
