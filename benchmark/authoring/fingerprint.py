"""Fingerprints of sessions and suites, so that results of different suites (the public one
and a lab's private split drawn with `bench generate --seed SECRET`) are never pooled unawares.

A session's fingerprint is the sha256 of its canonical session-file text (the bytes
`bench generate` writes), its first 16 hex digits; every result record carries it. A suite's
fingerprint hashes the sorted (session id, fingerprint) pairs of its sessions.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from benchmark.authoring.session_file import (
    FINGERPRINT_CHARS,
    Session,
    dump_session,
    text_fingerprint,
)

__all__ = ["FINGERPRINT_CHARS", "MixedSuitesError", "check_poolable", "session_fingerprint",
           "suite_fingerprint", "suite_fingerprint_of_files"]

class MixedSuitesError(ValueError):
    """Records of one session id carry different fingerprints: they come from different
    suites (say a public and a private split) and their scores must not be pooled."""


def session_fingerprint(session: Session) -> str:
    """The fingerprint of a loaded session (that of its canonical file text)."""
    return session.fingerprint


def suite_fingerprint(pairs: Iterable[tuple[str, str]]) -> str:
    """The fingerprint of a suite from its (session id, session fingerprint) pairs."""
    lines = "".join(f"{sid} {fp}\n" for sid, fp in sorted(set(pairs)))
    return text_fingerprint(lines)


def suite_fingerprint_of_files(paths: Iterable[Path]) -> str:
    """The fingerprint of the suite made of these session files (as written)."""
    import json
    pairs = []
    for path in paths:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
        pairs.append((str(data["id"]), text_fingerprint(dump_session(data))))
    return suite_fingerprint(pairs)


def check_poolable(records: Iterable[Mapping[str, Any]], *, allow_mixed: bool = False
                   ) -> str | None:
    """The suite fingerprint of the records; raises MixedSuitesError when one session id
    carries two fingerprints, unless allow_mixed. Records without a fingerprint (older runs)
    are not compared; None when no record has one."""
    seen: dict[str, set[str]] = {}
    for r in records:
        fp = r.get("fingerprint")
        if isinstance(fp, str) and fp:
            seen.setdefault(str(r.get("session", "")), set()).add(fp)
    mixed = {sid: fps for sid, fps in seen.items() if len(fps) > 1}
    if mixed and not allow_mixed:
        sid, fps = sorted(mixed.items())[0]
        raise MixedSuitesError(
            f"the results mix suites: session {sid} was run from {len(fps)} different session "
            f"files (fingerprints {', '.join(sorted(fps))}; {len(mixed)} session(s) in all), "
            f"e.g. a public and a private split; report them apart, or pass --allow-mixed to "
            f"pool them anyway")
    if not seen:
        return None
    return suite_fingerprint((sid, fp) for sid, fps in seen.items() for fp in fps)
