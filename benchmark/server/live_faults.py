"""The hidden faults of a live session's current task (benchmark.authoring.task_faults), put in
force by
`mavswarm serve` exactly as `bench run` does: scheduled from the task's start in simulated time
when the task becomes current, and undone (failures still pending dropped, the session's own
link faults back) when an operator moves the session on. Both are recorded in the ground truth
as they happen. Nothing here is told to the agent: it notices a fault from telemetry and
outcomes."""

from __future__ import annotations

from benchmark.running.episode import session_link_faults
from benchmark.server.hub import LiveSession

__all__ = ["end_task_faults", "start_task_faults"]


def start_task_faults(live: LiveSession) -> None:
    """Schedule the current task's faults from `live.task_start_s` (nothing for a task
    without faults)."""
    faults = live.task.faults
    if faults is not None:
        faults.apply(live.swarm, live.task_start_s)


def end_task_faults(live: LiveSession) -> None:
    """The current task is over: drop its failures still pending and restore the session
    file's link faults (the links of a session with tasks cannot be changed while it runs:
    link_routes.link_refusal)."""
    faults = live.task.faults
    if faults is not None:
        faults.end(live.swarm, session_link_faults(live.session))
