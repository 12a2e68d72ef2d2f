"""The shipped benchmark sessions as the editor offers them: listed to open (by id, never by a
path a caller sends), and their ids reserved: a session saved from the editor under a shipped
session's id would mix its results with that session's, so saving one is refused."""

from __future__ import annotations

import functools
import re
from pathlib import Path
from typing import Any

from benchmark.authoring.scenarios import all_session_keys, session_id
from benchmark.authoring.suite import SESSIONS_DIR

__all__ = ["edited_id", "shipped_ids", "shipped_listing", "shipped_path"]


@functools.cache
def shipped_ids() -> tuple[str, ...]:
    """Every shipped session's id (family, level, index order)."""
    return tuple(session_id(*key) for key in all_session_keys())


def shipped_listing() -> list[dict[str, Any]]:
    """The shipped sessions there are files of: id, family, level and index."""
    return [{"id": session_id(*key), "family": key[0], "level": key[1], "index": key[2]}
            for key in all_session_keys() if shipped_path(session_id(*key)) is not None]


def shipped_path(ident: str) -> Path | None:
    """The file of the shipped session `ident` (None: no such shipped session)."""
    if ident not in shipped_ids():
        return None
    path = SESSIONS_DIR / f"{ident}.json"
    return path if path.is_file() else None


def edited_id(ident: str) -> str:
    """The id an edited copy of session `ident` is proposed under (`-edit` added once)."""
    base = re.sub(r"-edit(-\d+)?$", "", ident)
    return f"{base}-edit"
