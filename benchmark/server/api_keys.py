"""API keys for `mavswarm serve`: `role[:session[/drone]]=key` specs, generated keys, and
registering them on a Hub (a session with drone keys gets one agent thread per such drone)."""

from __future__ import annotations

import secrets
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from benchmark.server.agent_threads import ServedTools
from benchmark.server.hub import Hub, Role

__all__ = ["ApiKey", "add_keys", "generated_keys", "parse_api_key"]


@dataclass(frozen=True)
class ApiKey:
    """One API key: its role and, for an agent key, the session it is bound to (None: the
    only session served) and the drone whose agent it is (None: the session's agent)."""

    role: Role
    key: str
    session_id: str | None = None
    drone_id: str | None = None

    def spec(self) -> str:
        """The key in the `role[:session[/drone]]=key` form `parse_api_key` reads."""
        where = f":{self.session_id}" if self.session_id else ""
        drone = f"/{self.drone_id}" if self.drone_id else ""
        return f"{self.role.value}{where}{drone}={self.key}"


def parse_api_key(text: str) -> ApiKey:
    """Read `role[:session[/drone]]=key`, e.g. `agent:area_search-easy-1=s3cret`,
    `agent:area_search-easy-1/d2=k2` or `admin=root`."""
    if not isinstance(text, str) or "=" not in text:
        raise ValueError(f"api key: expected 'role[:session]=key', got {text!r}")
    head, key = text.split("=", 1)
    role_text, _, session_id = head.partition(":")
    try:
        role = Role(role_text.strip())
    except ValueError:
        raise ValueError(f"api key {text!r}: role must be one of "
                         f"{[r.value for r in Role]}, got {role_text!r}") from None
    if not key.strip():
        raise ValueError(f"api key {text!r}: the key after '=' is empty")
    if ":" in head and not session_id.strip():
        raise ValueError(f"api key {text!r}: the session after ':' is empty")
    if session_id and role is not Role.AGENT:
        raise ValueError(f"api key {text!r}: only agent keys name a session, not role "
                         f"{role.value!r}")
    session_id, slash, drone_id = session_id.partition("/")
    if slash and not (session_id.strip() and drone_id.strip()):
        raise ValueError(f"api key {text!r}: a drone's key names its session and drone "
                         "('agent:SESSION/DRONE=key')")
    return ApiKey(role, key.strip(), session_id.strip() or None, drone_id.strip() or None)


def generated_keys(session_ids: Sequence[str],
                   drones: Mapping[str, Sequence[str]] | None = None) -> list[ApiKey]:
    """Fresh random keys: one agent key per session (per drone of each session in `drones`),
    one operator key, one admin key."""
    owners: list[tuple[str, str | None]] = []
    for sid in session_ids:
        per_drone = list((drones or {}).get(sid, ()))
        owners += [(sid, d) for d in per_drone] if per_drone else [(sid, None)]
    keys = [ApiKey(Role.AGENT, secrets.token_urlsafe(18), sid, drone) for sid, drone in owners]
    keys.append(ApiKey(Role.OPERATOR, secrets.token_urlsafe(18)))
    keys.append(ApiKey(Role.ADMIN, secrets.token_urlsafe(18)))
    return keys


def add_keys(hub: Hub, keys: Sequence[ApiKey]) -> None:
    """Register `keys`; a session with drone keys gets one agent thread per such drone (and
    may then have no whole-session agent key, nor be open to keyless requests)."""
    per_drone: dict[str, list[str]] = {}
    whole: set[str] = set()
    for key in keys:
        session_id = key.session_id
        if key.role is Role.AGENT and session_id is None:
            if len(hub.sessions) != 1:
                raise ValueError(f"api key {key.role.value}=...: an agent key must name its "
                                 f"session when several are served "
                                 f"({', '.join(hub.sessions)})")
            session_id = next(iter(hub.sessions))
        try:
            hub.add_key(key.key, key.role, session_id, key.drone_id)
        except ValueError as error:
            raise ValueError(f"api key for role {key.role.value!r}: {error}") from None
        if key.role is Role.AGENT and key.drone_id is not None:
            drones = per_drone.setdefault(str(session_id), [])
            if key.drone_id not in drones:
                drones.append(key.drone_id)
        elif key.role is Role.AGENT:
            whole.add(str(session_id))
    if hub.open_access:
        whole.update(hub.sessions)
    for session_id, drones in per_drone.items():
        if session_id in whole:
            raise ValueError(f"session {session_id!r} has drone keys and a whole-session agent "
                             "key (or --open): its agent is either one per drone or one for "
                             "all, not both")
        tools = hub.sessions[session_id].tools
        if isinstance(tools, ServedTools):
            tools.split(drones)
