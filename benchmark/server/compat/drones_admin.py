"""MultiUAV-Plat's operator drone routes (commands.md section 11), for operators and admins
(the reference's SYSTEM role; never an agent key, DECISIONS 15), refused with 409 while a
benchmark task runs (compat_write_guard):

- `POST /drones/land_all`: every airborne drone put on the ground below where it is (an
  operator reset, as between benchmark tasks), unless that spot is inside an obstacle's
  footprint (`blocked`); `POST /drones/charge_all`: every battery full. Both answer during a
  task too when they change nothing (every drone landed, or full), as at a task's start, where
  the reference's harness calls them;
- `POST /drones/{id}/battery` `{battery_level}`: the battery set (0-100 %);
- `PUT /drones/{id}` `{name, model, perceived_radius, task_radius, battery_level,
  home_position}`: those fields changed at once (perception, checks and records follow);
  the reference's other fields are 422 by name;
- `PUT /drones/{id}/position` `{x, y, z}`: with z = 0 the drone is placed on the ground there
  (an operator reset; refused inside an obstacle's footprint); with z > 0 it is flown there
  over MAVLink (taking off first when on the ground), as DECISIONS 1 wants: no teleports in
  the air. Answers the drone's record;
- `POST /drones` (the reference's registration fields): a new drone joins the running swarm
  as a new MAVLink vehicle (the next free system id, emulator.fleet_membership) and the
  gateway learns it, so `GET /drones` lists it and the agent tools fly it; answers its record;
- `DELETE /drones/{id}`: the drone leaves the swarm (it stops speaking; its ground truth ends
  there) and is 404 afterwards. Refused (409) for a drone a task's checks name, or the last.

Bodies are pydantic models: a bad one is 422 naming the field and changes nothing."""

import asyncio
import dataclasses
import math
import time
from collections.abc import Callable
from typing import Annotated, Any

import shapely
from fastapi import Depends, FastAPI, HTTPException, Query
from pydantic import BaseModel, ConfigDict, Field

from benchmark.server.auth import require
from benchmark.server.compat.commands import resolve_session
from benchmark.server.compat.drone_join import DroneBody, create_drone, delete_drone
from benchmark.server.compat.entities import compat_drone
from benchmark.server.compat.write_guard import refuse_writes
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from emulator.flight.operator import place_on_ground, set_battery
from llm_tools.input_limits import preview
from mavlink_gateway import DroneState, Status
from mavlink_vocabulary import FlightState

__all__ = ["BatteryBody", "DroneUpdate", "PositionBody", "add_compat_drone_admin_routes"]

SETTLE_WALL_S = 5.0
"""How long (wall seconds) a reset waits for the drones' telemetry to show it."""
FULL_PCT = 99.95


class BatteryBody(BaseModel):
    battery_level: float = Field(ge=0.0, le=100.0, description="percent")


class PositionBody(BaseModel):
    x: float
    y: float
    z: float = Field(0.0, ge=0.0, description="altitude above ground, m")


class _Home(BaseModel):
    x: float
    y: float
    z: float = Field(0.0, ge=0.0)


class DroneUpdate(BaseModel):
    """What `PUT /drones/{id}` changes on a flying vehicle; the reference's other fields are
    refused by name (its limits, status and position belong to the autopilot: position has
    `PUT /drones/{id}/position`)."""

    model_config = ConfigDict(extra="forbid")

    name: str | None = Field(None, min_length=1, max_length=200)
    model: str | None = Field(None, min_length=1, max_length=200)
    perceived_radius: float | None = Field(None, ge=1.0, le=10_000.0, description="m")
    task_radius: float | None = Field(None, ge=0.1, le=10_000.0, description="m")
    battery_level: float | None = Field(None, ge=0.0, le=100.0, description="percent")
    home_position: _Home | None = None


async def _update(live: LiveSession, drone_id: str, body: DroneUpdate) -> dict[str, Any]:
    """The drone's record after `body`: names and radii in the session's vehicle spec (the
    checks and records read it), radii as the autopilot's SIM_SENS_RAD / SIM_TASK_RAD, the
    battery and home on the vehicle."""
    ap = _autopilot(live, drone_id)
    spec = next(v for v in live.session.scenario.vehicles if v.id == drone_id)
    spec = dataclasses.replace(
        spec, name=body.name or spec.name, model=body.model or spec.model,
        perceived_radius_m=body.perceived_radius or spec.perceived_radius_m,
        task_radius_m=body.task_radius or spec.task_radius_m)
    if body.perceived_radius is not None:
        ap.set_param("SIM_SENS_RAD", body.perceived_radius)
    if body.task_radius is not None:
        ap.set_param("SIM_TASK_RAD", body.task_radius)
    scenario = live.session.scenario
    vehicles = tuple(spec if v.id == drone_id else v for v in scenario.vehicles)
    live.session = dataclasses.replace(
        live.session, scenario=dataclasses.replace(scenario, vehicles=vehicles))
    if body.home_position is not None:
        ap.home_m = (body.home_position.x, body.home_position.y, body.home_position.z)
        ap.listener.on_home_changed()
    if body.battery_level is not None:
        set_battery(ap, body.battery_level)
    live.swarm.send_all_telemetry()
    level, home = body.battery_level, body.home_position
    await _settle(live, lambda s: (level is None or abs(s.battery_pct - level) <= 1.0) and (
        home is None or math.hypot(s.home_x_m - home.x, s.home_y_m - home.y) < 0.5),
        [drone_id])
    return compat_drone(live, _state(live, drone_id))


def _autopilot(live: LiveSession, drone_id: str) -> Any:
    fleet = live.swarm.fleet
    k = fleet.index_by_id.get(drone_id)
    if k is None:
        raise HTTPException(404, f"unknown drone {preview(drone_id)} in session {live.id!r}; "
                            f"drones: {', '.join(live.gateway.drones)}")
    return fleet.autopilots[k]


def _blocker(live: LiveSession, x_m: float, y_m: float) -> str | None:
    """The name of an obstacle whose footprint holds (x, y), at any height."""
    point = shapely.Point(x_m, y_m)
    for obstacle in live.session.scenario.world.obstacles:
        if obstacle.footprint.intersects(point):
            return f"{obstacle.kind} obstacle '{obstacle.name}'"
    return None


def _state(live: LiveSession, drone_id: str) -> DroneState:
    state = live.gateway.drone_state(drone_id).state
    if state is None:
        raise HTTPException(404, f"unknown drone {preview(drone_id)} in session {live.id!r}")
    return state


async def _settle(live: LiveSession, shown: Callable[[DroneState], bool], ids: list[str]
                  ) -> None:
    """Wait until every drone of `ids` reports a state `shown` accepts (the reset reached
    its telemetry), sending telemetry again now and then; 504 after SETTLE_WALL_S."""
    deadline, resend = time.monotonic() + SETTLE_WALL_S, 0.0
    while True:
        lagging = [d for d in ids if not shown(_state(live, d))]
        if not lagging:
            return
        now = time.monotonic()
        if now > deadline:
            raise HTTPException(504, f"the telemetry of {', '.join(lagging)} did not show the "
                                "change in time; it is in force on the vehicles")
        if now > resend:
            live.swarm.send_all_telemetry()
            resend = now + 0.2
        await asyncio.sleep(0.01)


def _grounded(state: DroneState) -> bool:
    return state.flight_state == FlightState.ON_GROUND and state.altitude_m < 0.3


def _status(live: LiveSession, state: DroneState) -> str:
    return str(compat_drone(live, state)["status"])


async def land_all(live: LiveSession) -> dict[str, Any]:
    details, landed = [], []
    for state in live.gateway.list_drones():
        ap = _autopilot(live, state.drone)
        x, y, z = (float(v) for v in ap.position_m)
        entry = {"drone_id": state.drone, "drone_name": ap.spec.name,
                 "previous_status": _status(live, state), "previous_altitude": round(z, 2),
                 "new_status": _status(live, state), "new_altitude": round(z, 2),
                 "action": "already_on_ground", "reason": None}
        blocked = _blocker(live, x, y) if ap.fleet.airborne[ap.k] or z > 0.3 else None
        if blocked is not None:
            entry.update(action="blocked", reason=f"landing point inside {blocked}")
        elif ap.fleet.airborne[ap.k] or z > 0.3:
            place_on_ground(ap, x, y)
            landed.append(state.drone)
            entry.update(action="landed", new_status="idle", new_altitude=0.0)
        details.append(entry)
    live.swarm.send_all_telemetry()
    await _settle(live, _grounded, landed)
    count = {a: sum(d["action"] == a for d in details)
             for a in ("landed", "blocked", "already_on_ground")}
    return {"message": f"{count['landed']} drones landed, {count['blocked']} blocked, "
                       f"{count['already_on_ground']} already on the ground",
            "total_drones": len(details), "drones_landed": count["landed"],
            "drones_blocked": count["blocked"],
            "drones_already_grounded": count["already_on_ground"], "details": details}


async def charge_all(live: LiveSession) -> dict[str, Any]:
    details, charged = [], []
    for state in live.gateway.list_drones():
        ap = _autopilot(live, state.drone)
        before = float(ap.fleet.bat.pct[ap.k])
        full = before >= FULL_PCT
        if not full:
            set_battery(ap, 100.0)
            charged.append(state.drone)
        details.append({"drone_id": state.drone, "drone_name": ap.spec.name,
                        "previous_battery": round(before, 2), "new_battery": 100.0 if not full
                        else round(before, 2),
                        "action": "already_full" if full else "charged"})
    live.swarm.send_all_telemetry()
    await _settle(live, lambda s: s.battery_pct >= 99.0, charged)
    return {"message": f"{len(charged)} drones charged", "total_drones": len(details),
            "drones_charged": len(charged), "drones_already_full": len(details) - len(charged),
            "details": details}


async def _move(live: LiveSession, drone_id: str, body: PositionBody) -> dict[str, Any]:
    ap = _autopilot(live, drone_id)
    if body.z == 0.0:
        blocked = _blocker(live, body.x, body.y)
        if blocked is not None:
            raise HTTPException(409, f"Cannot place the drone: position conflicts with "
                                f"{blocked}")
        place_on_ground(ap, body.x, body.y)
        live.swarm.send_all_telemetry()
        await _settle(live, lambda s: _grounded(s) and abs(s.x_m - body.x) < 0.5
                      and abs(s.y_m - body.y) < 0.5, [drone_id])
        return compat_drone(live, _state(live, drone_id))
    if _state(live, drone_id).flight_state == FlightState.ON_GROUND:
        took = await live.gateway.take_off(drone_id, body.z)
        if took.status is not Status.OK:
            raise HTTPException(409, f"cannot take off to fly there: {took.message}")
    flown = await live.gateway.move_to(drone_id, body.x, body.y, body.z)
    if flown.status is not Status.OK:
        raise HTTPException(409, f"the drone did not get there: {flown.message}")
    return compat_drone(live, _state(live, drone_id))


def add_compat_drone_admin_routes(app: FastAPI, hub: Hub) -> None:
    staff = require(hub, Role.OPERATOR, Role.ADMIN)
    pick = Query(None, description="session id (operator and admin keys)")

    def writable(caller: Caller, session: str | None, what: str) -> LiveSession:
        live = resolve_session(hub, caller, session)
        refuse_writes(live, what)
        return live

    def unless_done(caller: Caller, session: str | None, done: Callable[[Any], bool]
                    ) -> LiveSession:
        """The session, refused during a task unless every drone is already as the reset
        would leave it (a harness resetting before a task changes nothing then)."""
        live = resolve_session(hub, caller, session)
        if not all(done(ap) for ap in live.swarm.fleet.autopilots):
            refuse_writes(live, "operator resets")
        return live

    @app.post("/drones/land_all", tags=["multiuav-plat"],
              summary="Put every airborne drone on the ground below it (operator, admin)")
    async def land_all_route(caller: Annotated[Caller, Depends(staff)],
                             session: str | None = pick) -> dict[str, Any]:
        return await land_all(unless_done(
            caller, session, lambda ap: not ap.fleet.airborne[ap.k]
            and float(ap.position_m[2]) <= 0.3))

    @app.post("/drones/charge_all", tags=["multiuav-plat"],
              summary="Fill every battery (operator, admin)")
    async def charge_all_route(caller: Annotated[Caller, Depends(staff)],
                               session: str | None = pick) -> dict[str, Any]:
        return await charge_all(unless_done(
            caller, session, lambda ap: float(ap.fleet.bat.pct[ap.k]) >= FULL_PCT))

    @app.post("/drones", tags=["multiuav-plat"],
              summary="Add a drone to the running swarm as a new MAVLink vehicle (operator, "
                      "admin)")
    async def create(body: DroneBody, caller: Annotated[Caller, Depends(staff)],
                     session: str | None = pick) -> dict[str, Any]:
        return await create_drone(writable(caller, session, "drone changes"), body)

    @app.delete("/drones/{drone_id}", tags=["multiuav-plat"],
                summary="Take a drone out of the running swarm (operator, admin)")
    async def delete(drone_id: str, caller: Annotated[Caller, Depends(staff)],
                     session: str | None = pick) -> dict[str, Any]:
        return await delete_drone(writable(caller, session, "drone changes"), drone_id)

    @app.post("/drones/{drone_id}/battery", tags=["multiuav-plat"],
              summary="Set a drone's battery level (operator, admin)")
    async def battery(drone_id: str, body: BatteryBody,
                      caller: Annotated[Caller, Depends(staff)], session: str | None = pick
                      ) -> dict[str, Any]:
        live = writable(caller, session, "battery changes")
        set_battery(_autopilot(live, drone_id), body.battery_level)
        live.swarm.send_all_telemetry()
        await _settle(live, lambda s: abs(s.battery_pct - body.battery_level) <= 1.0,
                      [drone_id])
        return compat_drone(live, _state(live, drone_id))

    @app.put("/drones/{drone_id}", tags=["multiuav-plat"],
             summary="Change a drone's name, model, radii, battery or home (operator, admin)")
    async def update(drone_id: str, body: DroneUpdate,
                     caller: Annotated[Caller, Depends(staff)], session: str | None = pick
                     ) -> dict[str, Any]:
        return await _update(writable(caller, session, "drone changes"), drone_id, body)

    @app.put("/drones/{drone_id}/position", tags=["multiuav-plat"],
             summary="Place a drone on the ground (z = 0) or fly it there (operator, admin)")
    async def position(drone_id: str, body: PositionBody,
                       caller: Annotated[Caller, Depends(staff)], session: str | None = pick
                       ) -> dict[str, Any]:
        return await _move(writable(caller, session, "drone moves by an operator"), drone_id,
                           body)
