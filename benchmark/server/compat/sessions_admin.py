"""MultiUAV-Plat's session lifecycle routes (entities.md section 8), for operators and admins:

- `POST /sessions` (a session in the reference's export layout, or a mavswarm session): a new
  8-hex id is given, its swarm starts and it becomes current, as `POST /sessions/load` does;
- `POST /sessions/{id}` (restore with that id): the same under the path's id; a session
  already live under it is not overwritten (409: its swarm runs; reset it or load another);
- `PUT /sessions/{id}` `{name, description}`: renames or describes a live session;
- `DELETE /sessions/{id}`: stops a live session (its agent's tools close, its swarm and
  gateway shut down) and forgets it; another becomes current only when one is picked (or
  one is left);
- `POST /sessions/current/reset` and `POST /sessions/{id}/reset`: statistics, reaches,
  coverage, tracking and the command, status and path histories start again from now (a new
  window, DECISIONS 9); entities, positions and batteries are untouched. Refused (409) while a
  benchmark task runs (compat_write_guard).

Bodies go through the same reading as `/sessions/load` (422 naming the field)."""

import dataclasses
import secrets
from typing import Annotated, Any

from fastapi import Depends, FastAPI, HTTPException, Query
from pydantic import BaseModel, ConfigDict, Field

from benchmark.server.auth import live_session, require
from benchmark.server.compat.commands import resolve_session
from benchmark.server.compat.entities import compat_session_fields
from benchmark.server.compat.write_guard import refuse_writes
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from benchmark.server.session_loading import load_session, session_body
from benchmark.server.session_runner import session_from_json
from llm_tools.input_limits import preview

__all__ = ["RESERVED_IDS", "SessionPatch", "add_compat_session_admin_routes", "reset_window"]

RESERVED_IDS = frozenset({"current", "load"})
"""Path words of the session routes, which cannot be session ids."""


class SessionPatch(BaseModel):
    """What `PUT /sessions/{id}` changes of a live session: its name and description (the
    world, drones and tasks have their own routes; the task type is the file's)."""

    model_config = ConfigDict(extra="forbid")

    name: str | None = Field(None, min_length=1, max_length=200)
    description: str | None = Field(None, max_length=10_000)


def reset_window(live: LiveSession) -> float:
    """Start the session's statistics and histories again from now; returns the time."""
    live.task_start_s = live.services.clock_s()
    return live.task_start_s


def _metadata(hub: Hub, live: LiveSession, role: Role, notes: list[str]) -> dict[str, Any]:
    fields = compat_session_fields(live, role, active=hub.current() == live.id)
    return {"id": live.id, "name": live.session.name, **fields, "notes": notes}


async def _create(hub: Hub, body: Any, ident: str, role: Role) -> dict[str, Any]:
    if not isinstance(body, dict) or not isinstance(body.get("name"), str) \
            or not body["name"].strip():
        raise HTTPException(422, "name: required, a non-empty string (the body is a session "
                            "in the reference's export layout)")
    if ident in RESERVED_IDS:
        raise HTTPException(422, f"session id {ident!r} is a word of the session routes")
    try:
        session, notes = session_from_json({**body, "id": ident}, "the body")
    except ValueError as error:
        raise HTTPException(422, str(error)) from None
    live = await load_session(hub, session)
    return _metadata(hub, live, role, notes)


def add_compat_session_admin_routes(app: FastAPI, hub: Hub) -> None:
    staff = require(hub, Role.OPERATOR, Role.ADMIN)
    pick = Query(None, description="session id (operator and admin keys)")

    @app.post("/sessions/current/reset", tags=["multiuav-plat"],
              summary="Start the current session's statistics and histories again (operator, "
                      "admin)")
    def reset_current(caller: Annotated[Caller, Depends(staff)], session: str | None = pick
                      ) -> dict[str, Any]:
        live = resolve_session(hub, caller, session)
        refuse_writes(live, "session resets")
        return {"message": f"session {live.id} reset", "id": live.id,
                "window_start_s": reset_window(live)}

    @app.post("/sessions/{session_id}/reset", tags=["multiuav-plat"],
              summary="Start a session's statistics and histories again (operator, admin)")
    def reset(session_id: str, caller: Annotated[Caller, Depends(staff)]) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        refuse_writes(live, "session resets")
        return {"message": f"session {live.id} reset", "id": live.id,
                "window_start_s": reset_window(live)}

    @app.put("/sessions/{session_id}", tags=["multiuav-plat"],
             summary="Rename or describe a session (operator, admin)")
    def update(session_id: str, body: SessionPatch, caller: Annotated[Caller, Depends(staff)]
               ) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        refuse_writes(live, "session changes")
        changes = body.model_dump(exclude_none=True)
        data = {**live.session.data, **changes}
        live.session = dataclasses.replace(live.session, data=data,
                                           name=changes.get("name", live.session.name))
        return _metadata(hub, live, caller.role, [])

    @app.delete("/sessions/{session_id}", tags=["multiuav-plat"],
                summary="Stop a live session and forget it (operator, admin)")
    async def delete(session_id: str, caller: Annotated[Caller, Depends(staff)]
                     ) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        refuse_writes(live, "session deletion")
        if hub.stopper is None:
            raise HTTPException(501, "this server cannot stop sessions while it runs")
        del hub.sessions[live.id]
        if hub.current_id == live.id:
            hub.current_id = None
        await live.tools.close()
        await hub.stopper(live.id)
        return {"message": f"session {live.id} deleted", "id": live.id,
                "current": hub.current(), "sessions": list(hub.sessions)}

    @app.post("/sessions", tags=["multiuav-plat"],
              summary="Create a session from the reference's layout and start it (operator, "
                      "admin)")
    async def create(caller: Annotated[Caller, Depends(staff)],
                     body: Annotated[Any, Depends(session_body)]) -> dict[str, Any]:
        ident = secrets.token_hex(4)
        while ident in hub.sessions:
            ident = secrets.token_hex(4)
        return await _create(hub, body, ident, caller.role)

    @app.post("/sessions/{session_id}", tags=["multiuav-plat"],
              summary="Create a session under this id and start it (operator, admin)")
    async def restore(session_id: str, caller: Annotated[Caller, Depends(staff)],
                      body: Annotated[Any, Depends(session_body)]) -> dict[str, Any]:
        if session_id in hub.sessions:
            raise HTTPException(409, f"session {preview(session_id)} is live; a live session "
                                "is not overwritten (reset it, or load the file under another "
                                "id)")
        return await _create(hub, body, session_id, caller.role)
