"""Response payloads per role. What an agent sees never includes targets, obstacles, check
trees or oracle plans; perception reaches it only through its drones' sensors."""

from __future__ import annotations

from typing import Any

from benchmark.server.hub import LiveSession, Role

__all__ = ["session_view", "task_view"]

_HIDDEN_TASK_KEYS = ("checks", "oracle", "faults")


def _summary(live: LiveSession) -> dict[str, Any]:
    s = live.session
    return {"id": s.id, "name": s.name, "task_type": s.task_type,
            "map_size_m": s.data.get("map_size_m"), "drones": list(live.gateway.drones),
            "current_task": live.task.id}


def task_view(live: LiveSession, role: Role) -> dict[str, Any]:
    """The current task: its text for an agent; budget and progress for an operator; the
    whole task, check tree, oracle and scheduled faults included, for an admin."""
    task = live.task
    view: dict[str, Any] = {"id": task.id, "text": task.text}
    if role is Role.AGENT:
        return view
    budget = task.budget
    view.update({"template": task.template, "category": task.category,
                 "difficulty": task.difficulty,
                 "budget": None if budget is None else {"tool_calls": budget.tool_calls,
                                                        "sim_time_s": budget.sim_time_s},
                 "tool_calls": live.tools.tool_calls,
                 "sim_elapsed_s": round(live.tools.sim_elapsed_s, 3),
                 "finished": live.tools.finished})
    if role is Role.ADMIN:
        raw = next((t for t in live.session.data.get("tasks", [])
                    if isinstance(t, dict) and t.get("id") == task.id), {})
        view.update({k: raw.get(k) for k in _HIDDEN_TASK_KEYS})
    return view


def session_view(live: LiveSession, role: Role) -> dict[str, Any]:
    """A session: a summary and the task text for an agent; the global map (targets,
    obstacles) for an operator; the whole session file for an admin."""
    view = _summary(live)
    view["task"] = task_view(live, role)
    if role is Role.AGENT:
        return view
    data = live.session.data
    view.update({"family": live.session.family, "level": live.session.level,
                 "environment": data.get("environment"), "targets": data.get("targets", []),
                 "obstacles": data.get("obstacles", []),
                 "tasks": [t.id for t in live.session.tasks]})
    if role is Role.ADMIN:
        view["data"] = data
    return view
