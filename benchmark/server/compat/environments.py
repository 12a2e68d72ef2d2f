"""MultiUAV-Plat's environment routes (entities.md section 5) over a live session: the
session file's environment is its current one; operators and admins list, create, update,
delete and pick environments (refused with 409 while a benchmark task runs,
compat_write_guard). The current environment's wind drives the physics from the next step on
(the vehicles' wind, as the session file's wind does); weather never drifts (DECISIONS 5).

`GET /environments/{id}` answers every role (the weather is no secret); the rest is for
operators and admins. The current environment, and the last one, cannot be deleted (409).
Bodies are pydantic models (422 naming the field)."""

import dataclasses
import secrets
from typing import Annotated, Any, Literal

import numpy as np
from fastapi import Depends, FastAPI, HTTPException, Query
from pydantic import BaseModel, Field

from benchmark.server.auth import require
from benchmark.server.compat.commands import resolve_session
from benchmark.server.compat.records import full_record
from benchmark.server.compat.write_guard import refuse_writes
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from emulator.scenario import WIND_DIRECTIONS_DEG
from emulator.world import Wind
from llm_tools.input_limits import preview

__all__ = ["EnvironmentBody", "EnvironmentPatch", "add_compat_environment_routes",
           "environments"]

Weather = Literal["clear", "partly_cloudy", "cloudy", "rain", "heavy_rain", "snow", "fog",
                  "windy", "storm"]
Direction = Literal["north", "northeast", "east", "southeast", "south", "southwest", "west",
                    "northwest"]


class EnvironmentPatch(BaseModel):
    """Fields of an environment to change (all optional)."""

    name: str | None = Field(None, min_length=1)
    weather: Weather | None = None
    temperature: float | None = Field(None, ge=-100.0, le=100.0, description="degrees C")
    humidity: float | None = Field(None, ge=0.0, le=100.0, description="percent")
    pressure: float | None = Field(None, gt=0.0, description="hPa")
    wind_speed: float | None = Field(None, ge=0.0, le=100.0, description="m/s")
    wind_direction: Direction | None = None
    visibility: float | None = Field(None, ge=0.0, description="m")


class EnvironmentBody(EnvironmentPatch):
    """A new environment (its name required, the reference's defaults for the rest)."""

    name: str = Field(min_length=1)


def environments(live: LiveSession) -> dict[str, dict[str, Any]]:
    """The session's environment records by id, the current one first."""
    if not live.environments:
        current = full_record("environment", live.session.data.get("environment") or {})
        current["id"] = current.get("id") or secrets.token_hex(4)
        live.environments[current["id"]] = current
        _store_current(live, current)
    return live.environments


def _current_id(live: LiveSession) -> str:
    return str((live.session.data.get("environment") or {}).get("id"))


def _store_current(live: LiveSession, record: dict[str, Any]) -> None:
    """`record` as the session's environment, its wind on the vehicles."""
    data = {**live.session.data, "environment": dict(record)}
    live.session = dataclasses.replace(live.session, data=data)
    wind = Wind(float(record["wind_speed"]), WIND_DIRECTIONS_DEG[record["wind_direction"]])
    live.swarm.fleet.dyn.wind_m_s = np.asarray(wind.velocity_enu_m_s(), dtype=float)


def _one(live: LiveSession, environment_id: str) -> dict[str, Any]:
    found = environments(live).get(environment_id)
    if found is None:
        raise HTTPException(404, f"unknown environment {preview(environment_id)}; "
                            f"environments: {', '.join(environments(live))}")
    return found


def add_compat_environment_routes(app: FastAPI, hub: Hub) -> None:
    anyone = require(hub, Role.AGENT, Role.OPERATOR, Role.ADMIN)
    staff = require(hub, Role.OPERATOR, Role.ADMIN)
    pick = Query(None, description="session id (operator and admin keys)")

    def writable(caller: Caller, session: str | None) -> LiveSession:
        live = resolve_session(hub, caller, session)
        refuse_writes(live, "environment changes")
        return live

    @app.get("/environments", tags=["multiuav-plat"],
             summary="The session's environments (operator, admin)")
    def listed(caller: Annotated[Caller, Depends(staff)], session: str | None = pick
               ) -> list[dict[str, Any]]:
        return list(environments(resolve_session(hub, caller, session)).values())

    @app.get("/environments/{environment_id}", tags=["multiuav-plat"],
             summary="One environment")
    def one(environment_id: str, caller: Annotated[Caller, Depends(anyone)],
            session: str | None = pick) -> dict[str, Any]:
        return _one(resolve_session(hub, caller, session), environment_id)

    @app.post("/environments", tags=["multiuav-plat"],
              summary="Add an environment (operator, admin)")
    def create(body: EnvironmentBody, caller: Annotated[Caller, Depends(staff)],
               session: str | None = pick) -> dict[str, Any]:
        live = writable(caller, session)
        table = environments(live)
        record = full_record("environment", body.model_dump(exclude_none=True))
        record["id"] = secrets.token_hex(4)
        table[record["id"]] = record
        return record

    @app.put("/environments/{environment_id}", tags=["multiuav-plat"],
             summary="Change an environment (operator, admin)")
    def update(environment_id: str, body: EnvironmentPatch,
               caller: Annotated[Caller, Depends(staff)], session: str | None = pick
               ) -> dict[str, Any]:
        live = writable(caller, session)
        record = {**_one(live, environment_id), **body.model_dump(exclude_none=True)}
        live.environments[environment_id] = record
        if environment_id == _current_id(live):
            _store_current(live, record)
        return record

    @app.delete("/environments/{environment_id}", tags=["multiuav-plat"],
                summary="Remove an environment, not the current one (operator, admin)")
    def delete(environment_id: str, caller: Annotated[Caller, Depends(staff)],
               session: str | None = pick) -> dict[str, Any]:
        live = writable(caller, session)
        _one(live, environment_id)
        if environment_id == _current_id(live):
            raise HTTPException(409, f"environment {environment_id} is the current one; make "
                                "another current first")
        del live.environments[environment_id]
        return {"message": f"environment {environment_id} deleted", "id": environment_id}

    @app.post("/environments/{environment_id}/set-current", tags=["multiuav-plat"],
              summary="Make an environment current: its wind drives the physics (operator, "
                      "admin)")
    def set_current(environment_id: str, caller: Annotated[Caller, Depends(staff)],
                    session: str | None = pick) -> dict[str, Any]:
        live = writable(caller, session)
        record = _one(live, environment_id)
        _store_current(live, record)
        return record
