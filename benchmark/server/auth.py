"""API-key authentication and role checks: 401 for a missing or unknown key, 403 for a role
(or an agent's session) that may not use a route."""


from collections.abc import Callable
from typing import Annotated

from fastapi import Depends, HTTPException, Security
from fastapi.security import APIKeyHeader

from benchmark.server.hub import Caller, Hub, LiveSession, Role
from llm_tools.input_limits import preview

__all__ = ["API_KEY_HEADER", "caller_dependency", "key_header", "live_session", "require"]

API_KEY_HEADER = "X-API-Key"

key_header = APIKeyHeader(name=API_KEY_HEADER, auto_error=False,
                       description="API key; its role is agent, operator or admin")


def caller_dependency(hub: Hub) -> Callable[..., Caller]:
    """A FastAPI dependency giving the Caller of a request's API key."""

    def caller(key: Annotated[str | None, Security(key_header)]) -> Caller:
        if not key:
            keyless = hub.keyless_caller()
            if keyless is not None:
                return keyless
            raise HTTPException(401, f"missing API key: send it in the {API_KEY_HEADER} header",
                                headers={"WWW-Authenticate": "APIKey"})
        found = hub.caller(key)
        if found is None:
            raise HTTPException(401, f"unknown API key in the {API_KEY_HEADER} header",
                                headers={"WWW-Authenticate": "APIKey"})
        return found

    return caller


def require(hub: Hub, *roles: Role) -> Callable[..., Caller]:
    """A dependency that admits only callers with one of `roles`."""
    allowed = ", ".join(r.value for r in roles)
    authenticate = caller_dependency(hub)

    def check(caller: Annotated[Caller, Depends(authenticate)]) -> Caller:
        if caller.role not in roles:
            raise HTTPException(403, f"role {caller.role.value!r} may not use this route; "
                                f"it needs one of: {allowed}")
        return caller

    check.roles = frozenset(roles)  # type: ignore[attr-defined]  # read by the role docs
    return check


def live_session(hub: Hub, caller: Caller, session_id: str) -> LiveSession:
    """The session a caller asked for: 403 for an agent asking for another session than its
    own (whether or not it exists), 404 for an unknown id."""
    if caller.role is Role.AGENT and caller.session_id != session_id:
        raise HTTPException(403, f"this agent key is bound to session {caller.session_id!r}, "
                            f"not {preview(session_id)}")
    live = hub.sessions.get(session_id)
    if live is None:
        raise HTTPException(404, f"unknown session {preview(session_id)}; sessions: "
                            f"{', '.join(hub.sessions) or 'none'}")
    return live
