"""MultiUAV-Plat's task routes over a live session's tasks (entities.md section 7,
perception_and_roles.md section 2), in the reference's task shape (`compat_task`):

- reads: `GET /sessions/current/tasks/{id}` (an agent: its current task only, masked),
  `GET /sessions/{id}/tasks` and `/sessions/{id}/tasks/{task_id}` (operators, admins);
- edits (operators, admins; 409 while a benchmark task runs, see compat_write_guard):
  `POST /sessions/{id}/tasks` (a task in the reference's shape, validated like an imported
  one), `PUT` and `DELETE /sessions/{id}/tasks/{task_id}`, `POST /sessions/{id}/tasks/swap`
  (`{task_id_1, task_id_2}`); the current task is never edited;
- marks (operators, admins): `POST /sessions/{current|id}/tasks/{task_id}/mark-done` and
  `mark-pending` set `is_done`;
- checks (admins only, DECISIONS 10): `GET /sessions/current/tasks/{id}/check` and
  `GET /check/task/{id}` evaluate the task's hidden checks on the current task's window;
  `is_passed` becomes true once they pass."""

import dataclasses
from typing import Annotated, Any, Literal

from fastapi import Depends, FastAPI, HTTPException, Query
from pydantic import BaseModel, ConfigDict, Field

from benchmark.authoring.importer import DEFAULT_BUDGET
from benchmark.authoring.session_file import TaskSpec, task_from_dict
from benchmark.scoring.validators import evaluate
from benchmark.scoring.validators.registry import endpoint_name
from benchmark.server.auth import live_session, require
from benchmark.server.compat.commands import resolve_session
from benchmark.server.compat.session_data import compat_task
from benchmark.server.compat.statistics import check_context
from benchmark.server.compat.write_guard import refuse_writes
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from llm_tools.input_limits import preview

__all__ = ["TaskBody", "TaskSwap", "add_compat_task_routes"]


class TaskBody(BaseModel):
    """A task as the reference's `POST /sessions/{id}/tasks` takes it."""

    model_config = ConfigDict(extra="ignore")

    name: str = Field(min_length=1)
    content: str = Field(min_length=1, description="the instruction given to the agent")
    content_aliases: list[str] = []
    description: str = ""
    creator: str = "system"
    originated_from: str | None = None
    difficulty: Literal["easy", "medium", "hard"] = "medium"
    related_apis: list[dict[str, Any]] = []
    execution_check_apis: dict[str, Any] | None = None
    commands: list[str] = []


class TaskSwap(BaseModel):
    """Two tasks of a session whose places are exchanged."""

    task_id_1: str = Field(min_length=1)
    task_id_2: str = Field(min_length=1)


def _tree(node: Any) -> Any:
    """A reference check tree with our endpoint names (no `/check/` prefix)."""
    if not isinstance(node, dict):
        return node
    out = dict(node)
    if isinstance(out.get("endpoint"), str):
        out["endpoint"] = endpoint_name(out["endpoint"])
    if isinstance(out.get("checks"), list):
        out["checks"] = [_tree(child) for child in out["checks"]]
    return out


def _raw_task(ident: str, body: TaskBody) -> dict[str, Any]:
    checks = body.execution_check_apis or {"logic": "and", "checks": []}
    return {"id": ident, "template": body.name, "category": body.description or "api",
            "difficulty": body.difficulty, "text": body.content,
            "aliases": list(body.content_aliases), "budget": dict(DEFAULT_BUDGET),
            "checks": _tree(checks), "oracle": None,
            "source": body.originated_from or body.creator}


def _index(live: LiveSession, task_id: str) -> int:
    found = next((k for k, t in enumerate(live.session.tasks) if t.id == task_id), None)
    if found is None:
        raise HTTPException(404, f"unknown task {preview(task_id)} in session {live.id!r}; "
                            f"tasks: {', '.join(t.id for t in live.session.tasks) or 'none'}")
    return found


def _spec(live: LiveSession, k: int, raw: dict[str, Any]) -> TaskSpec:
    spec = task_from_dict(k, raw, live.session.scenario)
    if spec.error is not None:
        raise HTTPException(422, spec.error)
    return spec


def _replace(live: LiveSession, tasks: list[TaskSpec], raws: list[Any]) -> None:
    """The session with `tasks` (and their file records `raws`) in this order."""
    data = {**live.session.data, "tasks": raws}
    live.session = dataclasses.replace(live.session, tasks=tuple(tasks), data=data)


def _raws(live: LiveSession) -> list[Any]:
    by_id = {t.get("id"): t for t in live.session.data.get("tasks", []) if isinstance(t, dict)}
    return [by_id.get(t.id, {"id": t.id}) for t in live.session.tasks]


def _editable(live: LiveSession, task_id: str | None, what: str) -> None:
    refuse_writes(live, what)
    if task_id is not None and task_id == live.task.id:
        raise HTTPException(409, f"task {task_id} is the session's current task; move the "
                            "session on before changing it")


def _new_id(live: LiveSession) -> str:
    taken = {t.id for t in live.session.tasks}
    k = len(taken) + 1
    while f"task-{k:03d}" in taken:
        k += 1
    return f"task-{k:03d}"


def _check(live: LiveSession, task_id: str, role: Role) -> dict[str, Any]:
    k = _index(live, task_id)
    task = live.session.tasks[k]
    if task.checks is None:
        raise HTTPException(409, f"task {task.id!r} has no valid checks: {task.error}")
    ctx = check_context(live)
    result = evaluate(task.checks, ctx)
    if result.passed:
        live.task_marks.setdefault(task.id, {})["is_passed"] = True
    return {"result": result.passed, "task": compat_task(live, k, role),
            "details": result.to_json(), "window_s": [ctx.t0_s, ctx.t1_s]}


def _mark(live: LiveSession, task_id: str, role: Role, done: bool) -> dict[str, Any]:
    k = _index(live, task_id)
    live.task_marks.setdefault(task_id, {})["is_done"] = done
    return compat_task(live, k, role)


def _add_mark_routes(app: FastAPI, hub: Hub, staff: Any, done: bool) -> None:
    word = "done" if done else "pending"
    pick = Query(None, description="session id (operator and admin keys)")

    def current_mark(task_id: str, caller: Annotated[Caller, Depends(staff)],
                     session: str | None = pick) -> dict[str, Any]:
        return _mark(resolve_session(hub, caller, session), task_id, caller.role, done)

    def mark(session_id: str, task_id: str, caller: Annotated[Caller, Depends(staff)]
             ) -> dict[str, Any]:
        return _mark(live_session(hub, caller, session_id), task_id, caller.role, done)

    summary = f"Mark a task {word} (operator, admin)"
    app.post(f"/sessions/current/tasks/{{task_id}}/mark-{word}", tags=["multiuav-plat"],
             summary=summary)(current_mark)
    app.post(f"/sessions/{{session_id}}/tasks/{{task_id}}/mark-{word}",
             tags=["multiuav-plat"], summary=summary)(mark)


def add_compat_task_routes(app: FastAPI, hub: Hub) -> None:
    anyone = require(hub, Role.AGENT, Role.OPERATOR, Role.ADMIN)
    staff = require(hub, Role.OPERATOR, Role.ADMIN)
    admin = require(hub, Role.ADMIN)
    pick = Query(None, description="session id (operator and admin keys)")

    @app.get("/sessions/current/tasks/{task_id}", tags=["multiuav-plat"],
             summary="One task (an agent: its current task, masked)")
    def current_task(task_id: str, caller: Annotated[Caller, Depends(anyone)],
                     session: str | None = pick) -> dict[str, Any]:
        live = resolve_session(hub, caller, session)
        if caller.role is Role.AGENT and task_id != live.task.id:
            raise HTTPException(404, f"no task {preview(task_id)} for you: your task is "
                                f"{live.task.id!r}")
        return compat_task(live, _index(live, task_id), caller.role)

    @app.get("/sessions/current/tasks/{task_id}/check", tags=["multiuav-plat"],
             summary="Evaluate one task's hidden checks now (admin)")
    def check_current(task_id: str, caller: Annotated[Caller, Depends(admin)],
                      session: str | None = pick) -> dict[str, Any]:
        return _check(resolve_session(hub, caller, session), task_id, caller.role)

    @app.get("/check/task/{task_id}", tags=["checks"],
             summary="Evaluate one task's hidden checks now (admin)")
    def check_task(task_id: str, caller: Annotated[Caller, Depends(admin)],
                   session: str | None = pick) -> dict[str, Any]:
        return _check(resolve_session(hub, caller, session), task_id, caller.role)

    for done in (True, False):
        _add_mark_routes(app, hub, staff, done)

    @app.get("/sessions/{session_id}/tasks", tags=["multiuav-plat"],
             summary="A session's tasks in order (operator, admin)")
    def tasks(session_id: str, caller: Annotated[Caller, Depends(staff)]
              ) -> list[dict[str, Any]]:
        live = live_session(hub, caller, session_id)
        return [compat_task(live, k, caller.role) for k in range(len(live.session.tasks))]

    @app.post("/sessions/{session_id}/tasks", tags=["multiuav-plat"],
              summary="Add a task at the end (operator, admin)")
    def create(session_id: str, body: TaskBody, caller: Annotated[Caller, Depends(staff)]
               ) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        _editable(live, None, "task edits")
        raws = _raws(live)
        raw = _raw_task(_new_id(live), body)
        spec = _spec(live, len(raws), raw)
        _replace(live, [*live.session.tasks, spec], [*raws, raw])
        return compat_task(live, len(raws), caller.role)

    @app.post("/sessions/{session_id}/tasks/swap", tags=["multiuav-plat"],
              summary="Exchange two tasks' places (operator, admin)")
    def swap(session_id: str, body: TaskSwap, caller: Annotated[Caller, Depends(staff)]
             ) -> list[dict[str, Any]]:
        live = live_session(hub, caller, session_id)
        _editable(live, None, "task edits")
        a, b = _index(live, body.task_id_1), _index(live, body.task_id_2)
        tasks, raws = list(live.session.tasks), _raws(live)
        tasks[a], tasks[b] = tasks[b], tasks[a]
        raws[a], raws[b] = raws[b], raws[a]
        _replace(live, tasks, raws)
        return [compat_task(live, k, caller.role) for k in range(len(tasks))]

    @app.get("/sessions/{session_id}/tasks/{task_id}", tags=["multiuav-plat"],
             summary="One task of a session (operator, admin)")
    def one(session_id: str, task_id: str, caller: Annotated[Caller, Depends(staff)]
            ) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        return compat_task(live, _index(live, task_id), caller.role)

    @app.put("/sessions/{session_id}/tasks/{task_id}", tags=["multiuav-plat"],
             summary="Replace a task (operator, admin)")
    def update(session_id: str, task_id: str, body: TaskBody,
               caller: Annotated[Caller, Depends(staff)]) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        _editable(live, task_id, "task edits")
        k = _index(live, task_id)
        tasks, raws = list(live.session.tasks), _raws(live)
        raws[k] = _raw_task(task_id, body)
        tasks[k] = _spec(live, k, raws[k])
        _replace(live, tasks, raws)
        live.task_marks.pop(task_id, None)
        return compat_task(live, k, caller.role)

    @app.delete("/sessions/{session_id}/tasks/{task_id}", tags=["multiuav-plat"],
                summary="Remove a task (operator, admin)")
    def delete(session_id: str, task_id: str, caller: Annotated[Caller, Depends(staff)]
               ) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        _editable(live, task_id, "task edits")
        k = _index(live, task_id)
        tasks, raws = list(live.session.tasks), _raws(live)
        del tasks[k], raws[k]
        _replace(live, tasks, raws)
        live.task_marks.pop(task_id, None)
        return {"message": f"task {task_id} deleted", "task_id": task_id,
                "remaining": [t.id for t in tasks]}
