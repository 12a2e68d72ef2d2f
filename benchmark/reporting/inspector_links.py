"""Links from reports into the run inspector that ``mavswarm replay RESULTS_DIR`` serves:
``{base}/inspect/{session}/{task}?run={run}&agent={agent}&trial={k}``, the run being the id the
replay server gives the results folder (its name), so a link opens that run's page even when
several runs are served."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any
from urllib.parse import quote, urlsplit

__all__ = ["DEFAULT_INSPECTOR_URL", "TaskLinks", "check_inspector_url", "inspector_link"]

DEFAULT_INSPECTOR_URL = "http://127.0.0.1:8765"


def check_inspector_url(url: str) -> str:
    """`url` without a trailing slash when it is an http(s) URL with a host; else ValueError
    saying what is expected."""
    parts = urlsplit(url.strip()) if isinstance(url, str) else None
    if parts is None or parts.scheme not in ("http", "https") or not parts.netloc:
        raise ValueError(f"--inspector-url must be an http(s) URL such as "
                         f"{DEFAULT_INSPECTOR_URL}, got {url!r}")
    return url.strip().rstrip("/")


def inspector_link(base: str, session: str, task: str, trial: int, *, run: str | None = None,
                   agent: str | None = None) -> str:
    """The inspector's page of one task:
    ``{base}/inspect/{session}/{task}?run={run}&agent={agent}&trial={trial}``, `run` (the id
    ``mavswarm replay`` gives the results folder) and `agent` only when given: with several
    runs served, the run picks whose page opens."""
    query = [("run", run), ("agent", agent), ("trial", str(int(trial)))]
    text = "&".join(f"{name}={quote(str(value), safe='')}" for name, value in query
                    if value is not None)
    return (f"{base.rstrip('/')}/inspect/{quote(str(session), safe='')}/"
            f"{quote(str(task), safe='')}?{text}")


@dataclass(frozen=True)
class TaskLinks:
    """Where task links point: the inspector's URL and the run id it knows the results by."""

    url: str
    run: str | None

    def of(self, record: Mapping[str, Any]) -> str:
        """The inspector page of a record: named by run and agent when the run is known."""
        return inspector_link(self.url, record["session"], record["task"],
                              record.get("trial", 0), run=self.run,
                              agent=None if self.run is None else record["agent"])
