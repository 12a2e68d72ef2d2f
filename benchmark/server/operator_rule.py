"""The one rule for operators acting on a served session: while a benchmark task runs for the
session's agent, whatever would change that task's result is refused (HTTP 409 where HTTP
answers). Flight commands from the web console, commands over MQTT and link changes all ask
`operator_refusal`; a world served without tasks takes them.
"""

from __future__ import annotations

from benchmark.server.hub import Hub, LiveSession

__all__ = ["operator_refusal", "served_refusal"]


def operator_refusal(live: LiveSession, what: str) -> str | None:
    """Why an operator's `what` ("flight commands from the console", "link changes", ...) may
    not act on `live` now, or None when they may."""
    if live.task.checks is None:  # a world without tasks (or a task that cannot be judged)
        return None
    return (f"session {live.id} is running benchmark task {live.task.id} for its agent; "
            f"{what} are refused while a task runs (they would change its result): serve a "
            "world without tasks to fly its drones or change its links by hand")


def served_refusal(hub: Hub, session_id: str, what: str) -> str | None:
    """`operator_refusal` of a session looked up in `hub` (one no longer served is refused)."""
    live = hub.sessions.get(session_id)
    if live is None:
        return f"session {session_id} is no longer served"
    return operator_refusal(live, what)
