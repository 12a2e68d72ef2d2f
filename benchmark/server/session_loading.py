"""Operators switch what a running server serves, as the reference's session controller does:
`POST /sessions/load` loads another session (a file in the server's session folders,
`benchmark.authoring.session_folders`, or the session JSON in the body; MultiUAV-Plat files are
converted as `bench import` converts them), starts its swarm and makes it current;
`POST /sessions/{id}/set-current` makes a live session current again. The current session is
the one the MultiUAV-Plat routes act on when no session is named, and the session of a
request without a key under `--open`. Agents cannot switch sessions (403), and a refused load
changes nothing."""

from typing import Annotated, Any

from fastapi import Depends, FastAPI, HTTPException

from benchmark.authoring.session_file import Session
from benchmark.authoring.session_folders import SessionFolders, SessionPathError
from benchmark.server.auth import live_session, require
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from benchmark.server.session_runner import first_task, session_from_json
from llm_tools.body_limit import json_body
from llm_tools.input_limits import MAX_SESSION_NUMBER_ABS, preview

__all__ = ["MAX_LIVE_SESSIONS", "add_session_loading_routes", "load_session"]

MAX_LIVE_SESSIONS = 16
"""Sessions a server runs at once: each is a swarm with its own UDP ports."""
_BODY_FORMS = ('{"path": "<session file in a session folder>"}, {"session": {...}} or a '
               "session object (mavswarm or MultiUAV-Plat)")
session_body = json_body(max_number_abs=MAX_SESSION_NUMBER_ABS)
"""A body that carries a session: the input bounds, with a session's number bound (its seed
is a 64-bit integer); its size is the body limit's (`BodyLimit`, 1 MiB)."""


async def _read(body: Any, folders: SessionFolders) -> tuple[Session, list[str]]:
    """The session a load request names, with the notes on what was mapped; HTTP 4xx for
    anything that is not a usable session (a path outside the session folders: 403)."""
    if not isinstance(body, dict):
        raise HTTPException(422, f"the body must be {_BODY_FORMS}; got {preview(body)}")
    try:
        if "path" in body or "session" in body:
            if len(body) != 1:
                raise HTTPException(422, "give either 'path' or 'session', nothing else "
                                    f"(got keys {preview(sorted(body))})")
            if "session" in body:
                return session_from_json(body["session"], "the body's session")
            path, data = await folders.read_async(body["path"])
            return session_from_json(data, str(path))
        if "drones" not in body and "schema" not in body:
            raise HTTPException(422, f"the body must be {_BODY_FORMS}; got an object with "
                                f"keys {preview(sorted(body))}")
        return session_from_json(body, "the body")
    except SessionPathError as error:
        raise HTTPException(error.http_status, str(error)) from None
    except ValueError as error:  # SessionFileError, SessionImportError, InputError
        raise HTTPException(422, str(error)) from None


async def load_session(hub: Hub, session: Session) -> LiveSession:
    """Start `session` and make it current; HTTP 409/422/501 (nothing changed) when it
    cannot be."""
    if hub.starter is None:
        raise HTTPException(501, "this server cannot load sessions while it runs")
    if session.id in hub.sessions:
        raise HTTPException(409, f"session {session.id!r} is already live; make it current "
                            f"with POST /sessions/{session.id}/set-current")
    if len(hub.sessions) >= MAX_LIVE_SESSIONS:
        raise HTTPException(409, f"{len(hub.sessions)} sessions are live, the most this "
                            "server runs at once")
    try:
        first_task(session)
        live = await hub.starter(session)
    except (ValueError, OSError) as error:  # an unusable first task, a parameter out of range
        raise HTTPException(422, f"{session.source}: the session cannot start: {error}"
                            ) from None
    hub.add_session(live)
    hub.current_id = live.id
    return live


def _answer(hub: Hub, live: LiveSession, notes: list[str]) -> dict[str, Any]:
    return {"id": live.id, "name": live.session.name, "status": "active",
            "task_type": live.session.task_type, "task": live.task.id,
            "drones": len(live.gateway.drones), "notes": notes, "current": hub.current(),
            "sessions": list(hub.sessions)}


def add_session_loading_routes(app: FastAPI, hub: Hub) -> None:
    staff = require(hub, Role.OPERATOR, Role.ADMIN)

    @app.post("/sessions/load", tags=["sessions"],
              summary="Load another session, start its swarm, make it current "
                      "(operator, admin)",
              description=f"The body is {_BODY_FORMS}. A MultiUAV-Plat file is converted as "
                          "`mavswarm bench import` converts it; `notes` says what was read "
                          "differently. A path is read from the session folders only "
                          "(benchmark/sessions, `--session-dir` folders, the files served): "
                          "403 outside them, 404 not there, 413 over 16 MiB, 422 not a "
                          "regular .json file or not a usable session (nothing changes); "
                          "409: its id is already live.")
    async def load(caller: Annotated[Caller, Depends(staff)],
                   body: Annotated[Any, Depends(session_body)]) -> dict[str, Any]:
        session, notes = await _read(body, hub.session_folders)
        live = await load_session(hub, session)
        return _answer(hub, live, notes)

    @app.post("/sessions/{session_id}/set-current", tags=["sessions"],
              summary="Make a live session the current one (operator, admin)")
    def set_current(session_id: str, caller: Annotated[Caller, Depends(staff)]
                    ) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        hub.current_id = live.id
        return _answer(hub, live, [])
