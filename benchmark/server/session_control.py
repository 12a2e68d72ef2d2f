"""What an operator (or admin) does to a live session besides watching it: move it on to its
next task, as the reference's session controller does. Agents cannot: their keys are bound to
a session, and the task they see is whatever the operator has put there."""

from typing import Annotated, Any

from fastapi import Depends, FastAPI, HTTPException

from benchmark.authoring.session_file import TaskSpec
from benchmark.running.episode import reset_for_task
from benchmark.server.auth import live_session, require
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from benchmark.server.live_faults import end_task_faults, start_task_faults
from benchmark.server.session_runner import task_tools

__all__ = ["add_session_control_routes", "next_task"]


async def next_task(live: LiveSession) -> tuple[TaskSpec, list[str]]:
    """Move `live` on to the next usable task after the current one: the agent's running
    primitives are cancelled, the current task's hidden faults undone (failures still pending
    dropped, the session's link back), the drones reset as before every benchmark task (landed
    where they are, failures repaired, batteries full, inboxes empty), and a fresh budget starts
    with the new task's hidden faults scheduled from its start. Returns the task and the ids of
    unusable tasks skipped; HTTP 409 when no usable task follows."""
    tasks = live.session.tasks
    index = next((k for k, t in enumerate(tasks) if t is live.task), -1)
    following = tasks[index + 1:] if index >= 0 else tasks  # free flight: the first task
    skipped: list[str] = []
    task: TaskSpec | None = None
    for candidate in following:
        if candidate.budget is not None:
            task = candidate
            break
        skipped.append(candidate.id)
    if task is None:
        raise HTTPException(409, f"no usable task follows {live.task.id!r} in session "
                            f"{live.id!r}" + (f" (unusable: {', '.join(skipped)})"
                                              if skipped else ""))
    assert task.budget is not None
    await live.tools.close()
    end_task_faults(live)
    await reset_for_task(live.swarm, live.services, live.gateway)
    live.task = task
    live.tools = task_tools(live.gateway, live.id, task,
                            drones=getattr(live.tools, "drone_threads", ()))
    live.task_start_s = live.services.clock_s()
    start_task_faults(live)
    return task, skipped


def add_session_control_routes(app: FastAPI, hub: Hub) -> None:
    staff = require(hub, Role.OPERATOR, Role.ADMIN)

    @app.post("/sessions/{session_id}/task/next", tags=["sessions"],
              summary="Move the session on to its next task (operator, admin)")
    async def advance(session_id: str, caller: Annotated[Caller, Depends(staff)]
                      ) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        task, skipped = await next_task(live)
        return {"session": live.id, "task": task.id, "text": task.text, "skipped": skipped,
                "task_start_s": live.task_start_s}
