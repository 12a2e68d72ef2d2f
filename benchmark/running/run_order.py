"""The order a benchmark run starts its sessions in, read from the session files before any
is loaded (an unreadable file sorts as an empty one; its worker reports the problem)."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from benchmark.running.worker_count import INSTANT_AGENTS

__all__ = ["run_order", "session_head"]


def session_head(path: Path) -> tuple[str | None, int, int]:
    """A session file's id, number of tasks and number of drones without validating it (an
    unreadable file: None, 0, 0; the worker reports the problem)."""
    data = _session_data(path)
    ident, tasks, drones = data.get("id"), data.get("tasks"), data.get("drones")
    return (ident if isinstance(ident, str) else None,
            len(tasks) if isinstance(tasks, list) else 0,
            len(drones) if isinstance(drones, list) else 0)


def _session_data(path: Path) -> dict[str, Any]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def _tool_call_budget(data: dict[str, Any]) -> int:
    """The tool calls a session's tasks allow in all (0 where a file does not say)."""
    total = 0
    for task in data.get("tasks") or []:
        budget = task.get("budget") if isinstance(task, dict) else None
        calls = budget.get("tool_calls") if isinstance(budget, dict) else None
        if isinstance(calls, int) and not isinstance(calls, bool) and calls > 0:
            total += calls
    return total


def run_order(sessions: Sequence[Path], agent: str) -> list[Path]:
    """The order a run with several workers starts sessions in: the longest first, since
    the run ends when its last session does (results do not depend on the order). An
    agent that answers at once (the oracle, noop) spends a session's time computing, which
    grows with its drones: the largest fleets first. Any other agent spends it thinking
    before each call, one call after another: the sessions whose tasks allow the most tool
    calls in all first (the fleet's size breaks ties)."""
    data = {p: _session_data(p) for p in sessions}
    drones = {p: len(d["drones"]) if isinstance(d.get("drones"), list) else 0
              for p, d in data.items()}
    if agent in INSTANT_AGENTS:
        return sorted(sessions, key=lambda p: -drones[p])
    return sorted(sessions, key=lambda p: (-_tool_call_budget(data[p]), -drones[p]))
