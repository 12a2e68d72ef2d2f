"""More MultiUAV-Plat compatible routes: the current session, its tasks (masked), the
environment, a generic command route, and targets or obstacles by id — for an agent, only
while one of its drones perceives them."""

from typing import Annotated, Any

from fastapi import Depends, FastAPI, HTTPException, Query, Request

from benchmark.server.auth import require
from benchmark.server.compat.commands import COMMANDS, resolve_session, run_command
from benchmark.server.compat.entities import compat_session_fields, entity_records
from benchmark.server.compat.records import full_record
from benchmark.server.compat.statistics import statistics_block
from benchmark.server.compat.write_guard import refuse_flight
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from benchmark.server.views import session_view, task_view
from llm_tools.input_limits import parse_json, preview
from llm_tools.registry import ToolRegistry

__all__ = ["add_compat_world_routes", "perceived_ids"]

_LIST_WORDS = frozenset({"type", "types", "waypoint", "waypoints", "fixed", "moving", "circle",
                         "polygon", "point", "ellipse", "all"})


def perceived_ids(live: LiveSession, kind: str) -> set[str]:
    """Ids of the entities of `kind` ("targets" or "obstacles") the session's drones sense now.
    Reads perception without charging the agent's budget: it is what the drones already
    report."""
    return {entity["id"] for drone in live.gateway.drones
            for entity in (live.gateway.nearby(drone).data or {}).get(kind, [])}


def _entity(live: LiveSession, caller: Caller, kind: str, entity_id: str) -> dict[str, Any]:
    """The entity's full record; for an agent only while its drones perceive it."""
    if entity_id in _LIST_WORDS:
        raise HTTPException(404, f"{preview(entity_id)} is not a {kind[:-1]} id; "
                            f"{kind} by type are at /{kind}/type/<type>")
    if caller.role is Role.AGENT and entity_id not in perceived_ids(live, kind):
        raise HTTPException(404, f"no {kind[:-1]} {preview(entity_id)} within your drones' "
                            "perception")
    record = entity_records(live, kind, (entity_id,)).get(entity_id)
    if record is None:
        raise HTTPException(404, f"unknown {kind[:-1]} {preview(entity_id)}")
    return dict(record)


def add_compat_world_routes(app: FastAPI, hub: Hub, registry: ToolRegistry) -> None:
    anyone = require(hub, Role.AGENT, Role.OPERATOR, Role.ADMIN)
    actor = require(hub, Role.AGENT, Role.OPERATOR, Role.ADMIN)
    pick = Query(None, description="session id (operator and admin keys)")

    @app.get("/sessions/current", tags=["multiuav-plat"], summary="The caller's session")
    def current(caller: Annotated[Caller, Depends(anyone)], session: str | None = pick
                ) -> dict[str, Any]:
        live = resolve_session(hub, caller, session)
        fields = compat_session_fields(live, caller.role, active=hub.current() == live.id)
        view = {**session_view(live, caller.role), **fields}
        if caller.role is not Role.AGENT:  # counts of the whole map
            view["statistics"] = statistics_block(live)
        return view

    @app.get("/sessions/current/tasks", tags=["multiuav-plat"],
             summary="The session's current task (masked for agents)")
    def tasks(caller: Annotated[Caller, Depends(anyone)], session: str | None = pick
              ) -> list[dict[str, Any]]:
        live = resolve_session(hub, caller, session)
        view = task_view(live, caller.role)
        return [{**view, "content": view["text"]}]

    @app.get("/environments/current", tags=["multiuav-plat"], summary="Weather and wind")
    def environment(caller: Annotated[Caller, Depends(anyone)], session: str | None = pick
                    ) -> dict[str, Any]:
        live = resolve_session(hub, caller, session)
        return full_record("environment", live.session.data.get("environment") or {})

    @app.get("/targets/{target_id}", tags=["multiuav-plat"], summary="A target by id")
    def target(target_id: str, caller: Annotated[Caller, Depends(anyone)],
               session: str | None = pick) -> dict[str, Any]:
        return _entity(resolve_session(hub, caller, session), caller, "targets", target_id)

    @app.get("/obstacles/{obstacle_id}", tags=["multiuav-plat"], summary="An obstacle by id")
    def obstacle(obstacle_id: str, caller: Annotated[Caller, Depends(anyone)],
                 session: str | None = pick) -> dict[str, Any]:
        return _entity(resolve_session(hub, caller, session), caller, "obstacles",
                       obstacle_id)

    @app.post("/drones/{drone_id}/command", tags=["multiuav-plat"],
              summary="A command named in the body: {command, parameters}")
    async def generic_command(drone_id: str, request: Request,
                              caller: Annotated[Caller, Depends(actor)],
                              session: str | None = pick) -> dict[str, Any]:
        body = parse_json(await request.body())
        if not isinstance(body, dict) or not isinstance(body.get("command"), str):
            raise HTTPException(422, "the body must be {\"command\": name, \"parameters\": "
                                f"{{...}}}}; commands: {', '.join(COMMANDS)}")
        params = body.get("parameters") or {}
        if not isinstance(params, dict):
            raise HTTPException(422, "parameters must be an object")
        live = resolve_session(hub, caller, session)
        refuse_flight(live, caller)
        scalars = {k: v for k, v in params.items() if not isinstance(v, list | dict)}
        return await run_command(live, registry, drone_id, body["command"], scalars,
                                 params or None)
