"""MultiUAV-Plat's entity shapes for the compatibility routes (spec: entities.md, and
perception_and_roles.md section 4). A drone: its static fields as its session file gives them
(name, model, limits, radii, the battery capacity label) and its live state from telemetry. A
perceived target or obstacle: its full record from the session file; only what the drone
perceives is ever looked up."""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

from benchmark.server.hub import LiveSession
from mavlink_gateway import DroneState

__all__ = ["compat_drone", "compat_nearby", "compat_session_fields"]

_FLIGHT = {"on_ground": "idle"}


def _file_record(live: LiveSession, kind: str, entity_id: str) -> Mapping[str, Any]:
    for record in live.session.data.get(kind, []):
        if isinstance(record, Mapping) and record.get("id") == entity_id:
            return record
    return {}


def compat_drone(live: LiveSession, state: DroneState) -> dict[str, Any]:
    """One drone as the reference returns it: every field of its entity record, with
    position, heading, battery and home from the drone's own telemetry. `speed` is 0.0 as in
    the reference, whose drones have no kinematics; times are epoch seconds."""
    spec = next((v for v in live.session.scenario.vehicles if v.id == state.drone), None)
    record = _file_record(live, "drones", state.drone)
    now = time.time()
    return {
        "id": state.drone,
        "name": spec.name if spec else state.drone,
        "model": spec.model if spec else "",
        "status": _FLIGHT.get(state.flight_state, state.flight_state),
        "position": {"x": round(state.x_m, 2), "y": round(state.y_m, 2),
                     "z": round(state.altitude_m, 2)},
        "heading": round(state.heading_deg, 1),
        "speed": 0.0,
        "perceived_radius": spec.perceived_radius_m if spec else None,
        "task_radius": spec.task_radius_m if spec else None,
        "battery_level": round(state.battery_pct, 2),
        "battery_capacity": record.get("battery_capacity",
                                       spec.battery_capacity_mah if spec else None),
        "max_speed": spec.max_speed_m_s if spec else None,
        "max_altitude": spec.max_altitude_m if spec else None,
        "home_position": {"x": round(state.home_x_m, 2), "y": round(state.home_y_m, 2),
                          "z": 0.0},
        "created_at": record.get("created_at", live.started_wall_s),
        "last_updated": now,
    }


def compat_nearby(live: LiveSession, perceived: Mapping[str, Any]) -> dict[str, Any]:
    """`{drones, targets, obstacles}` as the reference returns them: the full entity objects
    of what a drone perceives (`perceived` is the gateway's perception of that drone)."""
    states = {s.drone: s for s in live.gateway.list_drones()}
    drones = [compat_drone(live, states[e["id"]]) for e in perceived.get("drones", [])
              if e.get("id") in states]
    return {"drones": drones,
            **{kind: [dict(_file_record(live, kind, e["id"]) or e)
                      for e in perceived.get(kind, [])]
               for kind in ("targets", "obstacles")}}


def compat_session_fields(live: LiveSession) -> dict[str, Any]:
    """The reference's session metadata fields (entities.md section 6.1) for the live session:
    the one served is the current, active session; its map size is the canvas. Nothing here
    is more than an agent may read (no entity lists, no statistics)."""
    data = live.session.data
    width, height = (data.get("map_size_m") or [data.get("canvas_width", 1024),
                                                data.get("canvas_height", 768)])[:2]
    return {"description": data.get("description", ""), "creator": "system",
            "status": "active", "task_type": live.session.task_type,
            "task_description": live.task.text, "is_distance_3d": False,
            "canvas_width": width, "canvas_height": height,
            "created_at": live.started_wall_s, "last_updated": time.time()}
