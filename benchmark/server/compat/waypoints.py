"""MultiUAV-Plat's `POST /targets/waypoints/{id}/check-drone?drone_id=...`: whether a drone is
at a waypoint (a charging station): its 2D distance from the station's centre within the
station's radius, and whether it could charge there now (on the ground). The drone may also be
named in a JSON body `{"drone_id": ...}`. An agent asks only about stations its drones
perceive (404 otherwise), as for targets by id; operators and admins about any."""

import math
from typing import Annotated, Any

from fastapi import Body, Depends, FastAPI, HTTPException, Query

from benchmark.server.auth import require
from benchmark.server.compat.commands import resolve_session
from benchmark.server.compat.world import perceived_ids
from benchmark.server.hub import Caller, Hub, Role
from llm_tools.input_limits import preview
from mavlink_vocabulary import FlightState

__all__ = ["add_compat_waypoint_routes"]


def add_compat_waypoint_routes(app: FastAPI, hub: Hub) -> None:
    anyone = require(hub, Role.AGENT, Role.OPERATOR, Role.ADMIN)
    pick = Query(None, description="session id (operator and admin keys)")

    @app.post("/targets/waypoints/{waypoint_id}/check-drone", tags=["multiuav-plat"],
              summary="Whether a drone is at a waypoint (charging station)")
    def check_drone(waypoint_id: str, caller: Annotated[Caller, Depends(anyone)],
                    drone_id: str | None = Query(None, description="the drone"),
                    body: Annotated[dict[str, Any] | None, Body()] = None,
                    session: str | None = pick) -> dict[str, Any]:
        live = resolve_session(hub, caller, session)
        drone = drone_id or (body or {}).get("drone_id")
        if not isinstance(drone, str) or not drone:
            raise HTTPException(422, "drone_id: required (a query parameter or in the body)")
        world = live.session.scenario.world
        station = next((t for t in world.targets if t.id == waypoint_id
                        and t.is_charging_station), None)
        if station is None or (caller.role is Role.AGENT
                               and waypoint_id not in perceived_ids(live, "targets")):
            raise HTTPException(404, f"no waypoint {preview(waypoint_id)}"
                                + (" within your drones' perception"
                                   if caller.role is Role.AGENT else ""))
        state = live.gateway.drone_state(drone).state
        if state is None:
            raise HTTPException(404, f"unknown drone {preview(drone)} in session {live.id!r}")
        distance = math.hypot(state.x_m - station.position_m[0],
                              state.y_m - station.position_m[1])
        inside = distance <= station.radius_m + 1e-9
        return {"waypoint_id": station.id, "waypoint_name": station.name, "drone_id": drone,
                "is_at_waypoint": inside, "distance": round(distance, 2),
                "radius": station.radius_m,
                "can_charge": inside and state.flight_state == FlightState.ON_GROUND}
