"""Link faults of a live session at run time (operators and admins): read and change the loss,
latency with jitter, duplication, reordering and outage windows of every vehicle's link, per
direction (emulator.link_faults; docs/faults.md).

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
it. A task whose hidden part schedules faults (benchmark.authoring.task_faults) keeps them from
operators too: only an admin reads the link while it runs.
"""

from collections.abc import Callable
from dataclasses import dataclass
from typing import Annotated, Any

from fastapi import Depends, FastAPI, HTTPException, Request

from benchmark.server.auth import live_session, require
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from benchmark.server.operator_rule import operator_refusal
from emulator.link_faults import LinkFaultError
from emulator.services import SwarmServices
from llm_tools.input_limits import parse_json, preview

__all__ = ["LinkTarget", "add_link_api", "add_link_routes", "hidden_faults", "link_refusal",
           "session_link_target"]


@dataclass(frozen=True)
class LinkTarget:
    """The swarm a link request acts on: its services, why a change is refused now (None:
    it is not), and why this caller may not read the links now (None: it may)."""

    services: SwarmServices
    refusal: str | None = None
    unreadable: str | None = None


def link_refusal(live: LiveSession) -> str | None:
    """Why the session's links may not be changed now (benchmark.server.operator_rule), or
    None."""
    return operator_refusal(live, "link changes")


def hidden_faults(live: LiveSession) -> bool:
    """The current task's hidden part schedules faults (failures or link degradation)."""
    return live.task.faults is not None


def session_link_target(live: LiveSession, admin: bool) -> LinkTarget:
    """A live session's links as a staff caller (`admin` or not) may use them now."""
    unreadable = None
    if not admin and hidden_faults(live):
        unreadable = (f"task {live.task.id} of session {live.id} schedules faults in its "
                      "hidden part; only an admin reads the links while it runs")
    return LinkTarget(live.services, link_refusal(live), unreadable)


async def _body(request: Request) -> Any:
    raw = await request.body()
    if not raw.strip():
        raise HTTPException(422, "the body is empty; send the link settings as a JSON object")
    return parse_json(raw, "the body")


def _drone(services: SwarmServices, drone_id: str) -> str:
    if drone_id not in services.drone_ids:
        raise HTTPException(404, f"unknown drone {preview(drone_id)}; drones: "
                            f"{', '.join(services.drone_ids)}")
    return drone_id


def add_link_api(app: FastAPI, base: str, auth: Callable[..., Any],
                 target: Callable[[str, Any], LinkTarget], tag: str) -> None:
    """The four link routes under `base` (a path with a `{session_id}` parameter); `auth` is
    the dependency that admits staff, `target(session_id, who)` the swarm they act on."""
    Who = Annotated[Any, Depends(auth)]

    def readable(session_id: str, who: Any) -> LinkTarget:
        found = target(session_id, who)
        if found.unreadable is not None:
            raise HTTPException(403, found.unreadable)
        return found

    def changeable(session_id: str, who: Any) -> LinkTarget:
        found = target(session_id, who)
        if found.refusal is not None:
            raise HTTPException(409, found.refusal)
        return found

    def answer(session_id: str, services: SwarmServices, **fields: Any) -> dict[str, Any]:
        return {"session": session_id, "time_s": round(services.clock_s(), 3), **fields}

    @app.get(f"{base}/link-faults", tags=[tag],
             summary="The link faults in force (operator, admin)")
    def get_links(session_id: str, who: Who) -> dict[str, Any]:
        services = readable(session_id, who).services
        return answer(session_id, services, link_faults=services.operator_link_faults())

    @app.put(f"{base}/link-faults", tags=[tag],
             summary="Replace the link faults from now on (operator, admin)",
             description="The body is a session file's `link_faults` object: `seed`, profile "
                         "fields for both directions (`loss`, `latency_ms`, `jitter_ms`, "
                         "`duplicate`, `reorder`, `outages`), `uplink`/`downlink` objects, "
                         "`vehicles` (drone id -> the same). 422 names a bad field; 409 while "
                         "a benchmark task runs.")
    async def put_links(session_id: str, request: Request, who: Who) -> dict[str, Any]:
        services = changeable(session_id, who).services
        body = await _body(request)
        try:
            settings = services.operator_set_link_faults(body)
        except LinkFaultError as error:
            raise HTTPException(422, str(error)) from None
        return answer(session_id, services, link_faults=settings)

    @app.get(f"{base}/vehicles/{{drone_id}}/link", tags=[tag],
             summary="One vehicle's link in force (operator, admin)")
    def get_vehicle_link(session_id: str, drone_id: str, who: Who) -> dict[str, Any]:
        services = target(session_id, who).services
        drone = _drone(services, drone_id)
        services = readable(session_id, who).services
        return answer(session_id, services, drone=drone,
                      **services.operator_vehicle_link(drone))

    @app.put(f"{base}/vehicles/{{drone_id}}/link", tags=[tag],
             summary="Set one vehicle's own link settings from now on (operator, admin)",
             description="The body: profile fields for both directions (`loss`, "
                         "`latency_ms`, `jitter_ms`, `duplicate`, `reorder`, `outages` as "
                         "[start_s, end_s) simulated seconds), `uplink`/`downlink` objects "
                         "for one; fields not given take the swarm-wide settings. 422 names "
                         "a bad field; 409 while a benchmark task runs.")
    async def put_vehicle_link(session_id: str, drone_id: str, request: Request, who: Who
                               ) -> dict[str, Any]:
        drone = _drone(target(session_id, who).services, drone_id)
        services = changeable(session_id, who).services
        body = await _body(request)
        try:
            link = services.operator_set_vehicle_link(drone, body)
        except LinkFaultError as error:
            raise HTTPException(422, str(error)) from None
        return answer(session_id, services, drone=drone, **link)


def add_link_routes(app: FastAPI, hub: Hub) -> None:
    """The link routes of `mavswarm serve` under /sessions/{session_id}."""

    def target(session_id: str, caller: Caller) -> LinkTarget:
        return session_link_target(live_session(hub, caller, session_id),
                                   admin=caller.role is Role.ADMIN)

    add_link_api(app, "/sessions/{session_id}", require(hub, Role.OPERATOR, Role.ADMIN),
                 target, "links")
