"""Link faults of a live session at run time (operators and admins): read and change the loss,
latency with jitter, duplication, reordering and outage windows of every vehicle's link, per
direction (emulator.link_faults; README "Faults").

    GET /sessions/{id}/link-faults                 the settings in force
    PUT /sessions/{id}/link-faults                 replace them (a session file's
                                                   `link_faults` object)
    GET /sessions/{id}/vehicles/{drone}/link       one vehicle's uplink and downlink
    PUT /sessions/{id}/vehicles/{drone}/link       that vehicle's own settings (profile fields
                                                   for both directions, `uplink`/`downlink`
                                                   objects for one); the others keep theirs

A body is validated whole before anything changes: unknown fields, rates outside [0, 1],
latencies outside [0, 10,000] ms, outage windows that are not `[start_s, end_s)` in simulated
seconds, wrong types and numbers beyond the input bounds are a 422 naming the field. Agents
get no route here (403): a link degraded under them is something they notice from
telemetry and outcomes. While a benchmark task runs for the session's agent a change is
refused (409), since it would change the task's result; a world served without tasks takes
it. A task whose hidden part schedules faults (benchmark.task_faults) keeps them from
operators too: only an admin reads the link while it runs.
"""

from collections.abc import Mapping
from typing import Annotated, Any

from fastapi import Depends, FastAPI, HTTPException, Request

from benchmark.server.auth import live_session, require
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from emulator.link_faults import LinkFaultError
from llm_tools.input_limits import parse_json, preview

__all__ = ["add_link_routes", "hidden_faults", "link_refusal"]


def link_refusal(live: LiveSession) -> str | None:
    """Why the session's links may not be changed now (a benchmark task is running for its
    agent), or None."""
    if live.task.checks is None:
        return None
    return (f"session {live.id} is running benchmark task {live.task.id} for its agent; link "
            "changes are refused while a task runs (they would change its result): serve a "
            "world without tasks to change its links")


def hidden_faults(live: LiveSession) -> bool:
    """The current task's hidden part schedules faults (failures or link degradation)."""
    raw = next((t for t in live.session.data.get("tasks", [])
                if isinstance(t, Mapping) and t.get("id") == live.task.id), None)
    return isinstance(raw, Mapping) and raw.get("faults") is not None


def _readable(live: LiveSession, caller: Caller) -> None:
    if caller.role is not Role.ADMIN and hidden_faults(live):
        raise HTTPException(403, f"task {live.task.id} of session {live.id} schedules faults "
                            "in its hidden part; only an admin reads the links while it runs")


def _changeable(live: LiveSession) -> None:
    refusal = link_refusal(live)
    if refusal is not None:
        raise HTTPException(409, refusal)


async def _body(request: Request) -> Any:
    raw = await request.body()
    if not raw.strip():
        raise HTTPException(422, "the body is empty; send the link settings as a JSON object")
    return parse_json(raw, "the body")


def _drone(live: LiveSession, drone_id: str) -> str:
    if drone_id not in live.services.drone_ids:
        raise HTTPException(404, f"unknown drone {preview(drone_id)} in session {live.id!r}; "
                            f"drones: {', '.join(live.services.drone_ids)}")
    return drone_id


def add_link_routes(app: FastAPI, hub: Hub) -> None:
    staff = require(hub, Role.OPERATOR, Role.ADMIN)
    Staff = Annotated[Caller, Depends(staff)]

    @app.get("/sessions/{session_id}/link-faults", tags=["links"],
             summary="The link faults in force (operator, admin)")
    def get_links(session_id: str, caller: Staff) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        _readable(live, caller)
        return {"session": live.id, "time_s": round(live.services.clock_s(), 3),
                "link_faults": live.services.operator_link_faults()}

    @app.put("/sessions/{session_id}/link-faults", tags=["links"],
             summary="Replace the link faults from now on (operator, admin)",
             description="The body is a session file's `link_faults` object: `seed`, profile "
                         "fields for both directions (`loss`, `latency_ms`, `jitter_ms`, "
                         "`duplicate`, `reorder`, `outages`), `uplink`/`downlink` objects, "
                         "`vehicles` (drone id -> the same). 422 names a bad field; 409 while "
                         "a benchmark task runs.")
    async def put_links(session_id: str, request: Request, caller: Staff) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        _changeable(live)
        body = await _body(request)
        try:
            settings = live.services.operator_set_link_faults(body)
        except LinkFaultError as error:
            raise HTTPException(422, str(error)) from None
        return {"session": live.id, "time_s": round(live.services.clock_s(), 3),
                "link_faults": settings}

    @app.get("/sessions/{session_id}/vehicles/{drone_id}/link", tags=["links"],
             summary="One vehicle's link in force (operator, admin)")
    def get_vehicle_link(session_id: str, drone_id: str, caller: Staff) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        drone = _drone(live, drone_id)
        _readable(live, caller)
        return {"session": live.id, "drone": drone,
                "time_s": round(live.services.clock_s(), 3),
                **live.services.operator_vehicle_link(drone)}

    @app.put("/sessions/{session_id}/vehicles/{drone_id}/link", tags=["links"],
             summary="Set one vehicle's own link settings from now on (operator, admin)",
             description="The body: profile fields for both directions (`loss`, "
                         "`latency_ms`, `jitter_ms`, `duplicate`, `reorder`, `outages` as "
                         "[start_s, end_s) simulated seconds), `uplink`/`downlink` objects "
                         "for one; fields not given take the swarm-wide settings. 422 names "
                         "a bad field; 409 while a benchmark task runs.")
    async def put_vehicle_link(session_id: str, drone_id: str, request: Request,
                               caller: Staff) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        drone = _drone(live, drone_id)
        _changeable(live)
        body = await _body(request)
        try:
            link = live.services.operator_set_vehicle_link(drone, body)
        except LinkFaultError as error:
            raise HTTPException(422, str(error)) from None
        return {"session": live.id, "drone": drone,
                "time_s": round(live.services.clock_s(), 3), **link}
