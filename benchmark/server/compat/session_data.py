"""MultiUAV-Plat's session data and task progress routes.

`GET /sessions/current/data` and `GET /sessions/{id}/data` (operators and admins, as the
reference's SYSTEM role) give the flat session export: metadata, `statistics`, the drones with
their live state, the targets (moving ones where they are, with their tracking status),
obstacles and environment records, the tasks (check trees for admins only) and
`history.target_reaches` / `history.moving_target_tracking` / `history.area_coverage`.
`GET /sessions/current/task-progress` answers every role: operators and admins get the measured
progress; an agent gets the same keys with what the hidden checks decide left null.
`GET /sessions/{id}/task-progress` is for operators and admins."""

from collections.abc import Mapping
from typing import Annotated, Any

from fastapi import Depends, FastAPI, Query

from benchmark.server.auth import live_session, require
from benchmark.server.compat.commands import resolve_session
from benchmark.server.compat.entities import compat_drone, compat_session_fields, entity_records
from benchmark.server.compat.histories import session_histories
from benchmark.server.compat.records import full_record
from benchmark.server.compat.statistics import (
    agent_progress,
    check_context,
    reach_history,
    statistics_block,
    task_progress_block,
)
from benchmark.server.compat.tracking import moving_target_tracking
from benchmark.server.hub import Caller, Hub, LiveSession, Role

__all__ = ["add_compat_session_data_routes", "compat_task", "session_data"]


def _with_check_prefix(node: Any) -> Any:
    """A stored check tree with the reference's `/check/<endpoint>` names."""
    if not isinstance(node, Mapping):
        return node
    out = dict(node)
    if isinstance(out.get("endpoint"), str) and not out["endpoint"].startswith("/check/"):
        out["endpoint"] = f"/check/{out['endpoint']}"
    if isinstance(out.get("checks"), list):
        out["checks"] = [_with_check_prefix(child) for child in out["checks"]]
    return out


def compat_task(live: LiveSession, index: int, role: Role) -> dict[str, Any]:
    """Task `index` of the session in the reference's task shape. `is_done`: as mark-done or
    mark-pending set it, else whether the operator has moved the session past it.
    `is_passed`: set once an admin's task check passed (compat_tasks), else false. The check
    tree is for admins only; nobody gets `related_apis` (the oracle plan is in another
    shape)."""
    task = live.session.tasks[index]
    raw = next((t for t in live.session.data.get("tasks", [])
                if isinstance(t, Mapping) and t.get("id") == task.id), {})
    current = next((k for k, t in enumerate(live.session.tasks) if t is live.task), -1)
    marks = live.task_marks.get(task.id, {})
    checks = _with_check_prefix(raw.get("checks")) if role is Role.ADMIN else None
    return {"id": task.id, "name": task.template or task.id, "content": task.text,
            "content_aliases": list(task.aliases), "description": task.category,
            "creator": "system", "originated_from": raw.get("source", "system"),
            "difficulty": task.difficulty, "related_apis": [],
            "execution_check_apis": checks, "commands": [],
            "is_done": marks.get("is_done", index < current),
            "is_passed": marks.get("is_passed", False), "created_at": live.started_wall_s,
            "last_updated": live.started_wall_s}


def session_data(hub: Hub, live: LiveSession, role: Role) -> dict[str, Any]:
    """The reference's flat session export of a live session, for operators and admins."""
    data = live.session.data
    fields = compat_session_fields(live, role, active=hub.current() == live.id)
    reaches = reach_history(live)
    reached_by = {target: list(entry["reached_by"])
                  for target, entry in reaches["target_reaches"]["by_target"].items()}
    targets = [{**t, "is_reached": t["id"] in reached_by,
                "reached_by": reached_by.get(t["id"], [])}
               for t in entity_records(live, "targets").values()]
    return {"id": live.id, "name": live.session.name, **fields,
            "statistics": statistics_block(live),
            "drones": [compat_drone(live, s, volume=True) for s in live.gateway.list_drones()],
            "targets": targets,
            "obstacles": [dict(o) for o in entity_records(live, "obstacles").values()],
            "environment": full_record("environment", data.get("environment") or {}),
            "tasks": [compat_task(live, k, role) for k in range(len(live.session.tasks))],
            "history": {**session_histories(live), **reaches,
                        "moving_target_tracking": moving_target_tracking(check_context(live))}}


def add_compat_session_data_routes(app: FastAPI, hub: Hub) -> None:
    anyone = require(hub, Role.AGENT, Role.OPERATOR, Role.ADMIN)
    staff = require(hub, Role.OPERATOR, Role.ADMIN)
    pick = Query(None, description="session id (operator and admin keys)")

    @app.get("/sessions/current/data", tags=["multiuav-plat"],
             summary="The current session's complete data (operator, admin)")
    def current_data(caller: Annotated[Caller, Depends(staff)], session: str | None = pick
                     ) -> dict[str, Any]:
        return session_data(hub, resolve_session(hub, caller, session), caller.role)

    @app.get("/sessions/current/task-progress", tags=["multiuav-plat"],
             summary="Progress of the current task (for agents: no hidden-check results)")
    def current_progress(caller: Annotated[Caller, Depends(anyone)],
                         session: str | None = pick) -> dict[str, Any]:
        live = resolve_session(hub, caller, session)
        if caller.role is Role.AGENT:
            return agent_progress(live)
        return task_progress_block(live)

    @app.get("/sessions/{session_id}/data", tags=["multiuav-plat"],
             summary="A session's complete data (operator, admin)")
    def data(session_id: str, caller: Annotated[Caller, Depends(staff)]) -> dict[str, Any]:
        return session_data(hub, live_session(hub, caller, session_id), caller.role)

    @app.get("/sessions/{session_id}/task-progress", tags=["multiuav-plat"],
             summary="Progress of a session's current task (operator, admin)")
    def progress(session_id: str, caller: Annotated[Caller, Depends(staff)]
                 ) -> dict[str, Any]:
        return task_progress_block(live_session(hub, caller, session_id))
