"""Drones joining and leaving a running session (MultiUAV-Plat's `POST /drones` and
`DELETE /drones/{id}`, routed by compat_drones_admin): the swarm gains or loses a MAVLink
vehicle (emulator.fleet_membership), the gateway learns or forgets it, and the session's
records and scenario follow, so `GET /drones`, the checks and the agent tools see it."""

import dataclasses
import json
import secrets
import time
from collections.abc import Mapping
from typing import Any

from fastapi import HTTPException
from pydantic import BaseModel, ConfigDict, Field

from benchmark.server.compat.entities import compat_drone
from benchmark.server.hub import LiveSession
from emulator.fleet_membership import join, leave
from emulator.scenario import scenario_from_dict
from llm_tools.input_limits import preview
from mavlink_gateway import DroneProfile, DroneState, FleetError

__all__ = ["DroneBody", "create_drone", "delete_drone"]


def _state(live: LiveSession, drone_id: str) -> DroneState:
    state = live.gateway.drone_state(drone_id).state
    if state is None:
        raise HTTPException(404, f"unknown drone {preview(drone_id)} in session {live.id!r}")
    return state


class _Point(BaseModel):
    x: float
    y: float
    z: float = Field(0.0, ge=0.0, description="m above ground")


class DroneBody(BaseModel):
    """A drone to add to a running session: the reference's registration fields, with its
    defaults (perceived radius 100 m, task radius 10 m, battery 100 %)."""

    model_config = ConfigDict(extra="forbid")

    id: str | None = Field(None, min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.-]+$")
    name: str = Field(min_length=1, max_length=200)
    model: str = Field(min_length=1, max_length=200)
    position: _Point = Field(default_factory=lambda: _Point(x=0.0, y=0.0, z=0.0))
    heading: float = Field(0.0, allow_inf_nan=False, description="deg, kept mod 360")
    perceived_radius: float = Field(100.0, gt=0.0, le=10_000.0, description="m")
    task_radius: float = Field(10.0, gt=0.0, le=10_000.0, description="m")
    battery_level: float | None = Field(None, ge=0.0, le=100.0, description="percent")
    battery_volume: float | None = Field(None, ge=0.0, description="mAh")
    battery_capacity: float = Field(gt=0.0, le=1_000_000.0, description="mAh")
    max_speed: float = Field(gt=0.0, le=1_000.0, description="m/s")
    max_altitude: float = Field(gt=0.0, le=100_000.0, description="m")
    home_position: _Point | None = None


def _drone_records(live: LiveSession) -> list[dict[str, Any]]:
    return [dict(r) for r in live.session.data.get("drones", []) if isinstance(r, Mapping)]


async def create_drone(live: LiveSession, body: DroneBody) -> dict[str, Any]:
    """`body` as a new drone of the running swarm and the session."""
    taken = set(live.swarm.fleet.recorder.vehicle_ids)
    ident = body.id or secrets.token_hex(4)
    while body.id is None and ident in taken:
        ident = secrets.token_hex(4)
    if ident in taken:
        raise HTTPException(409, f"drone id {preview(ident)} is taken in this run (ids of "
                            "deleted drones are not reused)")
    record = {**body.model_dump(exclude_none=True), "id": ident, "created_at": time.time()}
    data = {**live.session.data, "drones": [*_drone_records(live), record]}
    try:
        spec = next(v for v in scenario_from_dict(data, source="the new drone").vehicles
                    if v.id == ident)
        k = join(live.swarm, spec)
    except ValueError as error:
        raise HTTPException(422 if "taken" not in str(error) else 409, str(error)) from None
    live.services.add_drone(ident)
    scenario = live.session.scenario
    live.session = dataclasses.replace(live.session, data=data, scenario=dataclasses.replace(
        scenario, vehicles=(*scenario.vehicles, spec)))
    try:
        await live.gateway.add_drone(DroneProfile(
            ident, spec.name, k + 1, spec.max_altitude_m, spec.max_speed_m_s,
            spec.perceived_radius_m, spec.task_radius_m))
    except (FleetError, RuntimeError) as error:
        await _remove(live, ident)
        raise HTTPException(503, f"the gateway did not find the new drone: {error}") from None
    return compat_drone(live, _state(live, ident))


async def _remove(live: LiveSession, drone_id: str) -> None:
    """`drone_id` out of the swarm, the gateway and the session."""
    leave(live.swarm, drone_id)
    live.services.remove_drone(drone_id)
    await live.gateway.remove_drone(drone_id)
    scenario = live.session.scenario
    live.session = dataclasses.replace(
        live.session,
        data={**live.session.data,
              "drones": [r for r in _drone_records(live) if r.get("id") != drone_id]},
        scenario=dataclasses.replace(
            scenario, vehicles=tuple(v for v in scenario.vehicles if v.id != drone_id)))


async def delete_drone(live: LiveSession, drone_id: str) -> dict[str, Any]:
    if drone_id not in live.swarm.fleet.index_by_id:
        raise HTTPException(404, f"unknown drone {preview(drone_id)} in session {live.id!r}")
    tasks = [str(t.get("id")) for t in live.session.data.get("tasks", [])
             if isinstance(t, Mapping) and f'"{drone_id}"' in json.dumps(t.get("checks"))]
    if tasks:
        raise HTTPException(409, f"the checks of task(s) {', '.join(tasks)} name drone "
                            f"{drone_id}")
    if len(live.swarm.fleet.index_by_id) == 1:
        raise HTTPException(409, f"drone {drone_id} is the session's last drone")
    await _remove(live, drone_id)
    return {"message": f"drone {drone_id} deleted", "id": drone_id}
