"""MultiUAV-Plat's target and obstacle writes (entities.md sections 3 and 4) on a live
session, for operators and admins, refused with 409 while a benchmark task runs
(compat_write_guard): `POST /targets`, `PUT /targets/{id}`, `DELETE /targets/{id}`, and the
same for `/obstacles`. The edited session is read again by the session loader (the same rules
as a file: 422 naming the entity and field, nothing changed) and the swarm flies in the new
world from the next physics step (emulator.world_edit): collision prevention, perception,
charging and the checks see it at once.

Refused as well (409): an obstacle over a drone at an altitude it blocks, deleting a target or
obstacle a task's checks name, and moving targets (they start with their session)."""

import dataclasses
import json
import secrets
from collections.abc import Mapping
from typing import Annotated, Any, Literal

import shapely
from fastapi import Depends, FastAPI, HTTPException, Query
from pydantic import BaseModel, ConfigDict, Field

from benchmark.server.auth import require
from benchmark.server.compat.commands import resolve_session
from benchmark.server.compat.records import full_record
from benchmark.server.compat.write_guard import refuse_writes
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from emulator.scenario import ScenarioError, scenario_from_dict
from emulator.world_edit import set_world
from llm_tools.input_limits import preview

__all__ = ["ObstacleBody", "ObstaclePatch", "TargetBody", "TargetPatch",
           "add_compat_world_admin_routes"]


class _Point(BaseModel):
    x: float
    y: float
    z: float = Field(0.0, ge=0.0)


class _Body(BaseModel):
    model_config = ConfigDict(extra="forbid")


class TargetPatch(_Body):
    """Fields of a still target to change."""

    name: str | None = Field(None, min_length=1)
    position: _Point | None = None
    description: str | None = None
    radius: float | None = Field(None, ge=0.0)
    vertices: list[_Point] | None = Field(None, min_length=3)
    charge_amount: float | None = Field(None, ge=0.0, le=100.0)


class TargetBody(TargetPatch):
    """A new still target (moving targets start with their session)."""

    name: str = Field(min_length=1)
    type: Literal["fixed", "waypoint", "circle", "polygon"]
    position: _Point


class ObstaclePatch(_Body):
    """Fields of an obstacle to change (not its type)."""

    name: str | None = Field(None, min_length=1)
    position: _Point | None = None
    description: str | None = None
    radius: float | None = Field(None, gt=0.0)
    width: float | None = Field(None, gt=0.0)
    length: float | None = Field(None, gt=0.0)
    vertices: list[_Point] | None = Field(None, min_length=3)
    height: float | None = Field(None, ge=0.0, description="0: blocks every altitude")


class ObstacleBody(ObstaclePatch):
    name: str = Field(min_length=1)
    type: Literal["point", "circle", "ellipse", "polygon"]
    position: _Point
    height: float = Field(0.0, ge=0.0, description="0: blocks every altitude")


def _records(live: LiveSession, kind: str) -> list[dict[str, Any]]:
    return [dict(r) for r in live.session.data.get(kind, []) if isinstance(r, Mapping)]


def _find(records: list[dict[str, Any]], kind: str, ident: str) -> int:
    found = next((k for k, r in enumerate(records) if r.get("id") == ident), None)
    if found is None:
        raise HTTPException(404, f"unknown {kind[:-1]} {preview(ident)}")
    return found


def _apply(live: LiveSession, kind: str, records: list[dict[str, Any]]) -> None:
    """The session with `records` as its `kind`, read again and flown from the next step."""
    data = {**live.session.data, kind: records}
    try:
        scenario = scenario_from_dict(data, source=f"the edited {kind}")
        if kind == "obstacles":
            _clear_of_drones(live, scenario.world.obstacles)
        set_world(live.swarm.fleet, scenario.world)
    except (ScenarioError, ValueError) as error:
        status = 409 if "moving targets" in str(error) else 422
        raise HTTPException(status, str(error)) from None
    live.session = dataclasses.replace(
        live.session, scenario=dataclasses.replace(live.session.scenario, world=scenario.world),
        data=data)


def _clear_of_drones(live: LiveSession, obstacles: Any) -> None:
    for state in live.gateway.list_drones():
        point = shapely.Point(state.x_m, state.y_m)
        for obstacle in obstacles:
            if obstacle.footprint.intersects(point) and obstacle.blocks_altitude(
                    state.altitude_m):
                raise HTTPException(409, f"obstacle {obstacle.name!r} would hold drone "
                                    f"{state.drone}; move the drone first")


def _named_by_tasks(live: LiveSession, ident: str) -> list[str]:
    return [str(t.get("id")) for t in live.session.data.get("tasks", [])
            if isinstance(t, Mapping) and f'"{ident}"' in json.dumps(t.get("checks"))]


def _plain(body: BaseModel) -> dict[str, Any]:
    return body.model_dump(exclude_none=True)


def add_compat_world_admin_routes(app: FastAPI, hub: Hub) -> None:
    staff = require(hub, Role.OPERATOR, Role.ADMIN)
    pick = Query(None, description="session id (operator and admin keys)")

    def writable(caller: Caller, session: str | None, kind: str) -> LiveSession:
        live = resolve_session(hub, caller, session)
        refuse_writes(live, f"{kind[:-1]} changes")
        return live

    def create(live: LiveSession, kind: str, body: BaseModel) -> dict[str, Any]:
        records = _records(live, kind)
        record = {"id": secrets.token_hex(4), **_plain(body)}
        _apply(live, kind, [*records, record])
        return full_record(kind, record)

    def update(live: LiveSession, kind: str, ident: str, body: BaseModel) -> dict[str, Any]:
        records = _records(live, kind)
        k = _find(records, kind, ident)
        if records[k].get("type") == "moving":
            raise HTTPException(409, "moving targets cannot be changed while the swarm flies")
        records[k] = {**records[k], **_plain(body)}
        _apply(live, kind, records)
        return full_record(kind, records[k])

    def delete(live: LiveSession, kind: str, ident: str) -> dict[str, Any]:
        records = _records(live, kind)
        k = _find(records, kind, ident)
        tasks = _named_by_tasks(live, ident)
        if tasks:
            raise HTTPException(409, f"the checks of task(s) {', '.join(tasks)} name "
                                f"{kind[:-1]} {ident}")
        del records[k]
        _apply(live, kind, records)
        return {"message": f"{kind[:-1]} {ident} deleted", "id": ident}

    @app.post("/targets", tags=["multiuav-plat"], summary="Add a target (operator, admin)")
    def create_target(body: TargetBody, caller: Annotated[Caller, Depends(staff)],
                      session: str | None = pick) -> dict[str, Any]:
        return create(writable(caller, session, "targets"), "targets", body)

    @app.put("/targets/{target_id}", tags=["multiuav-plat"],
             summary="Change a target (operator, admin)")
    def update_target(target_id: str, body: TargetPatch,
                      caller: Annotated[Caller, Depends(staff)], session: str | None = pick
                      ) -> dict[str, Any]:
        return update(writable(caller, session, "targets"), "targets", target_id, body)

    @app.delete("/targets/{target_id}", tags=["multiuav-plat"],
                summary="Remove a target (operator, admin)")
    def delete_target(target_id: str, caller: Annotated[Caller, Depends(staff)],
                      session: str | None = pick) -> dict[str, Any]:
        return delete(writable(caller, session, "targets"), "targets", target_id)

    @app.post("/obstacles", tags=["multiuav-plat"], summary="Add an obstacle (operator, admin)")
    def create_obstacle(body: ObstacleBody, caller: Annotated[Caller, Depends(staff)],
                        session: str | None = pick) -> dict[str, Any]:
        return create(writable(caller, session, "obstacles"), "obstacles", body)

    @app.put("/obstacles/{obstacle_id}", tags=["multiuav-plat"],
             summary="Change an obstacle, not its type (operator, admin)")
    def update_obstacle(obstacle_id: str, body: ObstaclePatch,
                        caller: Annotated[Caller, Depends(staff)], session: str | None = pick
                        ) -> dict[str, Any]:
        return update(writable(caller, session, "obstacles"), "obstacles", obstacle_id, body)

    @app.delete("/obstacles/{obstacle_id}", tags=["multiuav-plat"],
                summary="Remove an obstacle (operator, admin)")
    def delete_obstacle(obstacle_id: str, caller: Annotated[Caller, Depends(staff)],
                        session: str | None = pick) -> dict[str, Any]:
        return delete(writable(caller, session, "obstacles"), "obstacles", obstacle_id)
