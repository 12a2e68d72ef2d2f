"""Who may open the console: operator and admin keys see live swarms and command them; an
agent key is refused (the console shows the global map, which agents never get).

One check for every route and the live WebSocket (`check_connection`): the key comes from
the `X-API-Key` header or the `key` query parameter; no key or an unknown one (any text,
non-ASCII included) is 401, a key of another role 403. A refused WebSocket is accepted and
closed at once with close code 4000 + that status (4401, 4403; 4404 for an unknown live
swarm) and the same reason, so a browser's page can read why."""

from __future__ import annotations

import secrets
from collections.abc import Callable
from dataclasses import dataclass

from starlette.requests import HTTPConnection

__all__ = ["ConsoleAuth", "Verdict", "close_code"]

STAFF = ("operator", "admin")


@dataclass(frozen=True)
class Verdict:
    """The answer to a key: `role` when admitted, else the HTTP status and why."""

    role: str | None
    status: int = 200
    reason: str = ""


class ConsoleAuth:
    """Maps an API key to a role (`lookup(key) -> role or None`); only staff roles pass.
    `open_access` admits anyone (a replay server on this machine's own files)."""

    def __init__(self, lookup: Callable[[str], str | None], *, open_access: bool = False
                 ) -> None:
        self._lookup = lookup
        self.open_access = open_access

    @classmethod
    def single_key(cls, key: str | None = None) -> tuple[ConsoleAuth, str]:
        """An auth with one operator key (generated when not given), and that key."""
        key = key or secrets.token_urlsafe(16)
        expected = key.encode("utf-8")

        def lookup(given: str) -> str | None:  # bytes: compare_digest refuses non-ASCII text
            same = secrets.compare_digest(given.encode("utf-8", "surrogatepass"), expected)
            return "operator" if same else None

        return cls(lookup), key

    def check_connection(self, connection: HTTPConnection) -> Verdict:
        """`check` of a request's or WebSocket's key (`X-API-Key` header, else `key` query
        parameter)."""
        return self.check(connection.headers.get("x-api-key")
                          or connection.query_params.get("key"))

    def check(self, key: str | None) -> Verdict:
        if self.open_access:
            return Verdict("operator")
        if not key:
            return Verdict(None, 401, "missing API key: open the console with ?key=YOUR_KEY "
                                      "(an operator or admin key)")
        role = self._lookup(key)
        if role is None:
            return Verdict(None, 401, "unknown API key")
        if role not in STAFF:
            return Verdict(None, 403, f"role {role!r} may not open the console; it needs an "
                                      "operator or admin key")
        return Verdict(role)


def close_code(status: int) -> int:
    """The WebSocket close code of a refusal that HTTP answers with `status` (4401, ...)."""
    return 4000 + status
