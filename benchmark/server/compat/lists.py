"""MultiUAV-Plat's entity lists: `GET /targets`, `GET /targets/type/{type}`, `GET /obstacles`,
`GET /obstacles/type/{type}`, each a list of full entity records. Operators and admins get the
whole map; an agent gets only what its drones perceive now (the reference gives these lists
to its USER role, which an agent is not: the map beyond its sensors stays hidden)."""

from typing import Annotated, Any

from fastapi import Depends, FastAPI, HTTPException, Query

from benchmark.server.auth import require
from benchmark.server.compat.commands import resolve_session
from benchmark.server.compat.entities import entity_records
from benchmark.server.compat.world import perceived_ids
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from emulator.world import OBSTACLE_KINDS, TARGET_KINDS
from llm_tools.input_limits import preview

__all__ = ["add_compat_list_routes", "visible_records"]

_KINDS = {"targets": TARGET_KINDS, "obstacles": OBSTACLE_KINDS}


def visible_records(live: LiveSession, caller: Caller, kind: str) -> list[dict[str, Any]]:
    """The session file's records of `kind` ("targets" or "obstacles") the caller may see, in
    file order: all of them for operators and admins, what its drones perceive for an
    agent."""
    if caller.role is Role.AGENT:
        seen = perceived_ids(live, kind)
        records = entity_records(live, kind, seen)
        return [dict(r) for ident, r in records.items() if ident in seen]
    return [dict(r) for r in entity_records(live, kind).values()]


def _of_type(live: LiveSession, caller: Caller, kind: str, entity_type: str
             ) -> list[dict[str, Any]]:
    if entity_type not in _KINDS[kind]:
        raise HTTPException(422, f"unknown {kind[:-1]} type {preview(entity_type)}; types: "
                            f"{', '.join(_KINDS[kind])}")
    return [r for r in visible_records(live, caller, kind) if r.get("type") == entity_type]


def add_compat_list_routes(app: FastAPI, hub: Hub) -> None:
    anyone = require(hub, Role.AGENT, Role.OPERATOR, Role.ADMIN)
    pick = Query(None, description="session id (operator and admin keys)")

    @app.get("/targets", tags=["multiuav-plat"],
             summary="Targets (an agent: those its drones perceive)")
    def targets(caller: Annotated[Caller, Depends(anyone)], session: str | None = pick
                ) -> list[dict[str, Any]]:
        return visible_records(resolve_session(hub, caller, session), caller, "targets")

    @app.get("/targets/type/{target_type}", tags=["multiuav-plat"],
             summary="Targets of one type, e.g. waypoint (an agent: those it perceives)")
    def targets_of_type(target_type: str, caller: Annotated[Caller, Depends(anyone)],
                        session: str | None = pick) -> list[dict[str, Any]]:
        return _of_type(resolve_session(hub, caller, session), caller, "targets", target_type)

    @app.get("/obstacles", tags=["multiuav-plat"],
             summary="Obstacles (an agent: those its drones perceive)")
    def obstacles(caller: Annotated[Caller, Depends(anyone)], session: str | None = pick
                  ) -> list[dict[str, Any]]:
        return visible_records(resolve_session(hub, caller, session), caller, "obstacles")

    @app.get("/obstacles/type/{obstacle_type}", tags=["multiuav-plat"],
             summary="Obstacles of one type (an agent: those it perceives)")
    def obstacles_of_type(obstacle_type: str, caller: Annotated[Caller, Depends(anyone)],
                          session: str | None = pick) -> list[dict[str, Any]]:
        return _of_type(resolve_session(hub, caller, session), caller, "obstacles",
                        obstacle_type)
