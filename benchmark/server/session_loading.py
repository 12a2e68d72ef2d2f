"""Operators switch what a running server serves, as the reference's session controller does:
`POST /sessions/load` loads another session (a file on the server, or the session JSON in the
body; MultiUAV-Plat files are converted as `bench import` converts them), starts its swarm and
makes it current; `POST /sessions/{id}/set-current` makes a live session current again. The
current session is the one the MultiUAV-Plat routes act on when no session is named, and the
session of a request without a key under `--open`. Agents cannot switch sessions (403), and a
refused load changes nothing."""

import json
from pathlib import Path
from typing import Annotated, Any, NoReturn

from fastapi import Depends, FastAPI, HTTPException, Request

from benchmark.importer import load_any_session
from benchmark.server.auth import live_session, require
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from benchmark.server.session_runner import first_task, session_from_json
from benchmark.session_file import Session
from llm_tools.input_limits import check_text, preview

__all__ = ["MAX_LIVE_SESSIONS", "add_session_loading_routes", "load_session"]

MAX_LIVE_SESSIONS = 16
"""Sessions a server runs at once: each is a swarm with its own UDP ports."""
_PATH_CHARS = 4096
_BODY_FORMS = ('{"path": "<session file on the server>"}, {"session": {...}} or a session '
               "object (mavswarm or MultiUAV-Plat)")


def _not_finite(token: str) -> NoReturn:
    raise ValueError(f"{token} is not a JSON number")


def _parse(raw: bytes) -> Any:
    """The request body as JSON. A session file is not bounded like tool arguments (a seed
    exceeds their number limit); the body's size is (`BodyLimit`, 1 MiB)."""
    try:
        return json.loads(raw.decode("utf-8"), parse_constant=_not_finite)
    except UnicodeDecodeError as error:
        raise HTTPException(422, f"the body is not UTF-8 text (byte {error.start})") from None
    except json.JSONDecodeError as error:
        raise HTTPException(422, f"the body is not valid JSON ({error.msg} at character "
                            f"{error.pos})") from None
    except ValueError as error:
        raise HTTPException(422, f"the body: {error}") from None
    except RecursionError:
        raise HTTPException(422, "the body nests too deeply") from None


def _read(body: Any) -> tuple[Session, list[str]]:
    """The session a load request names, with the notes on what was mapped; HTTP 422 for
    anything that is not a usable session."""
    if not isinstance(body, dict):
        raise HTTPException(422, f"the body must be {_BODY_FORMS}; got {preview(body)}")
    try:
        if "path" in body or "session" in body:
            if len(body) != 1:
                raise HTTPException(422, "give either 'path' or 'session', nothing else "
                                    f"(got keys {preview(sorted(body))})")
            if "session" in body:
                return session_from_json(body["session"], "the body's session")
            path = body["path"]
            if not isinstance(path, str) or not path.strip():
                raise HTTPException(422, "path: expected the session file's path on the "
                                    f"server, got {preview(path)}")
            check_text(path, "path", limit=_PATH_CHARS)
            session, notes = load_any_session(Path(path))
            return session, notes
        if "drones" not in body and "schema" not in body:
            raise HTTPException(422, f"the body must be {_BODY_FORMS}; got an object with "
                                f"keys {preview(sorted(body))}")
        return session_from_json(body, "the body")
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
                          "differently. 422: not a usable session (nothing changes); 409: "
                          "its id is already live.")
    async def load(request: Request, caller: Annotated[Caller, Depends(staff)]
                   ) -> dict[str, Any]:
        session, notes = _read(_parse(await request.body()))
        live = await load_session(hub, session)
        return _answer(hub, live, notes)

    @app.post("/sessions/{session_id}/set-current", tags=["sessions"],
              summary="Make a live session the current one (operator, admin)")
    def set_current(session_id: str, caller: Annotated[Caller, Depends(staff)]
                    ) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        hub.current_id = live.id
        return _answer(hub, live, [])
