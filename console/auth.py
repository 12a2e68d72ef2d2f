"""Who may open the console: operator and admin keys see live swarms and command them; an
agent key is refused (the console shows the global map, which agents never get)."""

from __future__ import annotations

import secrets
from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["ConsoleAuth", "Verdict"]

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
        return cls(lambda given: "operator" if secrets.compare_digest(given, key) else None), key

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
