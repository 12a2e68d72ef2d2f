"""MultiUAV-Plat's request history (perception_and_roles.md section 5): every HTTP request is
recorded in the session it acted on (an agent key's session, else `?session=` or the current
one), at most MAX_RECORDS per session, in memory only (never exported). A record: request_id,
ISO timestamp, method, path, client ip and port, client_privilege (our role, upper case; null
for a refused key), authentication_status (`api_key`, `default_agent` for a keyless request
under `--open`, `invalid`, `missing`), session_id, query_params (a repeated key as a list),
user_agent, agent_id (`X-Agent-ID`, agents only), status_code, success (< 400), duration (s)
and error (the `detail` of a refused request is not kept: null). Request bodies are not
recorded. Not recorded, as in the reference: `GET /`, `GET /sessions/current/data`, resets and
request-history deletes.

Routes: `GET /sessions/current/request-history` (an agent: only its own records with its
`X-Agent-ID`), `GET /sessions/{id}/request-history` and the `DELETE`s of both (operators,
admins)."""

import secrets
import time
from collections import deque
from collections.abc import Awaitable, Callable
from datetime import UTC, datetime
from typing import Annotated, Any

from fastapi import Depends, FastAPI, Query, Request, Response

from benchmark.server.auth import API_KEY_HEADER, live_session, require
from benchmark.server.compat.commands import resolve_session
from benchmark.server.hub import Caller, Hub, Role

__all__ = ["MAX_RECORDS", "RequestLog", "add_compat_request_history"]

MAX_RECORDS = 5000
MAX_TEXT = 500
"""Longer paths, query values and user agents are cut to this many characters in a record."""
AGENT_ID_HEADER = "X-Agent-ID"
DEFAULT_AGENT_ID = "default_agent"


class RequestLog:
    """The request records of every session served, the newest last."""

    def __init__(self, hub: Hub) -> None:
        self.hub = hub
        self.by_session: dict[str, deque[dict[str, Any]]] = {}

    def who(self, request: Request) -> tuple[Caller | None, str]:
        """The caller of a request (None: refused) and how it was authenticated."""
        key = request.headers.get(API_KEY_HEADER)
        if not key:
            keyless = self.hub.keyless_caller()
            return keyless, "default_agent" if keyless else "missing"
        caller = self.hub.caller(key)
        return caller, "api_key" if caller else "invalid"

    def session_of(self, request: Request, caller: Caller | None) -> str | None:
        if caller is not None and caller.role is Role.AGENT:
            return caller.session_id
        named = request.query_params.get("session")
        if named in self.hub.sessions:
            return named
        parts = request.url.path.strip("/").split("/")
        if len(parts) >= 2 and parts[0] == "sessions" and parts[1] in self.hub.sessions:
            return parts[1]
        return self.hub.current()

    def record(self, request: Request, status: int, started_s: float) -> None:
        caller, how = self.who(request)
        session = self.session_of(request, caller)
        if session is None:
            return
        query: dict[str, Any] = {}
        for key in request.query_params:
            values = request.query_params.getlist(key)
            cut = [v[:MAX_TEXT] for v in values]
            query[key[:MAX_TEXT]] = cut if len(cut) > 1 else cut[0]
        client = request.client
        agent = caller is not None and caller.role is Role.AGENT
        entry = {
            "request_id": secrets.token_hex(4),
            "timestamp": datetime.now(UTC).isoformat(),
            "method": request.method, "path": request.url.path[:MAX_TEXT],
            "client_ip": client.host if client else None,
            "client_port": client.port if client else None,
            "client_privilege": caller.role.value.upper() if caller else None,
            "authentication_status": how, "session_id": session, "query_params": query,
            "user_agent": (request.headers.get("user-agent") or "")[:MAX_TEXT] or None,
            "agent_id": (request.headers.get(AGENT_ID_HEADER) or DEFAULT_AGENT_ID)[:128]
            if agent else None,
            "status_code": status, "success": status < 400,
            "duration": round(time.monotonic() - started_s, 6), "error": None}
        self.by_session.setdefault(session, deque(maxlen=MAX_RECORDS)).append(entry)


def _skipped(request: Request) -> bool:
    path = request.url.path.rstrip("/") or "/"
    return ((request.method == "GET" and path in ("/", "/sessions/current/data"))
            or path.endswith("/reset")
            or (request.method == "DELETE" and path.endswith("/request-history")))


def add_compat_request_history(app: FastAPI, hub: Hub) -> RequestLog:
    """Record every request of `app` and add the request-history routes."""
    log = RequestLog(hub)
    anyone = require(hub, Role.AGENT, Role.OPERATOR, Role.ADMIN)
    staff = require(hub, Role.OPERATOR, Role.ADMIN)
    pick = Query(None, description="session id (operator and admin keys)")
    limit = Query(100, ge=1, le=MAX_RECORDS, description="the newest records, at most")

    @app.middleware("http")
    async def record(request: Request, call_next: Callable[[Request], Awaitable[Response]]
                     ) -> Response:
        started = time.monotonic()
        response = await call_next(request)
        if not _skipped(request):
            log.record(request, response.status_code, started)
        return response

    def newest(session_id: str, count: int) -> list[dict[str, Any]]:
        return list(log.by_session.get(session_id, ()))[-count:]

    @app.get("/sessions/current/request-history", tags=["multiuav-plat"],
             summary="Requests recorded in the session (an agent: its own)")
    def current(request: Request, caller: Annotated[Caller, Depends(anyone)],
                session: str | None = pick, limit: int = limit) -> list[dict[str, Any]]:
        live = resolve_session(hub, caller, session)
        records = list(log.by_session.get(live.id, ()))
        if caller.role is Role.AGENT:
            label = (request.headers.get(AGENT_ID_HEADER) or DEFAULT_AGENT_ID)[:128]
            records = [r for r in records if r["client_privilege"] == "AGENT"
                       and r["agent_id"] == label]
        return records[-limit:]

    @app.get("/sessions/{session_id}/request-history", tags=["multiuav-plat"],
             summary="Requests recorded in a session (operator, admin)")
    def of_session(session_id: str, caller: Annotated[Caller, Depends(staff)],
                   limit: int = limit) -> list[dict[str, Any]]:
        return newest(live_session(hub, caller, session_id).id, limit)

    @app.delete("/sessions/current/request-history", tags=["multiuav-plat"],
                summary="Clear the current session's request history (operator, admin)")
    def clear_current(caller: Annotated[Caller, Depends(staff)], session: str | None = pick
                      ) -> dict[str, Any]:
        live = resolve_session(hub, caller, session)
        cleared = len(log.by_session.pop(live.id, ()))
        return {"message": f"{cleared} records cleared", "session_id": live.id,
                "cleared": cleared}

    @app.delete("/sessions/{session_id}/request-history", tags=["multiuav-plat"],
                summary="Clear a session's request history (operator, admin)")
    def clear(session_id: str, caller: Annotated[Caller, Depends(staff)]) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        cleared = len(log.by_session.pop(live.id, ()))
        return {"message": f"{cleared} records cleared", "session_id": live.id,
                "cleared": cleared}

    return log
