"""MultiUAV-Plat's entity shapes for the compatibility routes (spec: entities.md, and
perception_and_roles.md section 4). A drone: its static fields as its session file gives them
(name, model, limits, radii, the battery capacity label) and its live state from telemetry. A
perceived target or obstacle: its full record from the session file; only what the drone
perceives is ever looked up."""

from __future__ import annotations

import time
from collections.abc import Collection, Mapping
from typing import Any

from benchmark.server.compat.records import full_record
from benchmark.server.compat.statistics import check_context
from benchmark.server.compat.tracking import tracking_fields
from benchmark.server.hub import LiveSession, Role
from mavlink_gateway import DroneState

__all__ = ["compat_drone", "compat_nearby", "compat_session_fields", "entity_records"]

_FLIGHT = {"on_ground": "idle"}


def entity_records(live: LiveSession, kind: str, only: Collection[str] | None = None
                   ) -> dict[str, Mapping[str, Any]]:
    """The session file's records of `kind` ("drones", "targets" or "obstacles") by id; a
    moving target's `position` is where it is now, with its `tracking_status` and
    `last_tracked_at` in the current task's window (compat_tracking). `only`: the ids whose
    records are wanted (the others may come without their live fields)."""
    records: dict[str, Mapping[str, Any]] = {
        record["id"]: full_record(kind, record) for record in live.session.data.get(kind, [])
        if isinstance(record, Mapping) and isinstance(record.get("id"), str)}
    moving = live.swarm.fleet.targets if kind == "targets" else None
    if moving is not None:
        current = {ident: at for ident, at in moving.current().items()
                   if only is None or ident in only}
        ctx = check_context(live)
        for ident, (x, y, z) in current.items():
            if ident in records:
                records[ident] = {**records[ident], "position": {
                    "x": round(x, 2), "y": round(y, 2), "z": round(z, 2)},
                    **tracking_fields(ctx, ident)}
    return records


def _volume(level_pct: float, capacity: Any) -> float | None:
    """The reference's `battery_volume` (mAh left); None for a capacity that is a size label
    rather than a number."""
    if isinstance(capacity, bool) or not isinstance(capacity, int | float):
        return None
    return round(level_pct / 100.0 * float(capacity), 2)


def compat_drone(live: LiveSession, state: DroneState, *, volume: bool = False
                 ) -> dict[str, Any]:
    """One drone as the reference returns it: every field of its entity record, with
    position, heading, battery and home from the drone's own telemetry. `speed` is 0.0 as in
    the reference, whose drones have no kinematics; times are epoch seconds. `volume`: with
    the model's `battery_volume` (mAh left), as session data gives it (the reference's drone
    routes leave it out)."""
    spec = next(v for v in live.session.scenario.vehicles if v.id == state.drone)
    record = entity_records(live, "drones").get(state.drone, {})
    capacity = record.get("battery_capacity", spec.battery_capacity_mah)
    out = {
        "id": state.drone,
        "name": spec.name,
        "model": spec.model,
        "status": _FLIGHT.get(state.flight_state, state.flight_state),
        "position": {"x": round(state.x_m, 2), "y": round(state.y_m, 2),
                     "z": round(state.altitude_m, 2)},
        "heading": round(state.heading_deg, 1),
        "speed": 0.0,
        "perceived_radius": spec.perceived_radius_m,
        "task_radius": spec.task_radius_m,
        "battery_level": round(state.battery_pct, 2),
        "battery_capacity": capacity,
        "max_speed": spec.max_speed_m_s,
        "max_altitude": spec.max_altitude_m,
        "home_position": {"x": round(state.home_x_m, 2), "y": round(state.home_y_m, 2),
                          "z": 0.0},
        "created_at": record.get("created_at", live.started_wall_s),
        "last_updated": time.time(),
    }
    if volume:
        out["battery_volume"] = _volume(state.battery_pct, capacity)
    return out


def compat_nearby(live: LiveSession, perceived: Mapping[str, Any]) -> dict[str, Any]:
    """`{drones, targets, obstacles}` as the reference returns them: the full entity objects
    of what a drone perceives (`perceived` is the gateway's perception of that drone)."""
    states = {s.drone: s for s in live.gateway.list_drones()}
    drones = [compat_drone(live, states[e["id"]]) for e in perceived.get("drones", [])
              if e.get("id") in states]
    out: dict[str, Any] = {"drones": drones}
    for kind in ("targets", "obstacles"):
        records = entity_records(live, kind, {e["id"] for e in perceived.get(kind, [])})
        out[kind] = [dict(records.get(e["id"], e)) for e in perceived.get(kind, [])]
    return out


def compat_session_fields(live: LiveSession, role: Role, *, active: bool = True
                          ) -> dict[str, Any]:
    """The reference's session metadata fields (entities.md section 6.1) for the live session:
    `active` for the current session, else `inactive`; its map size is the canvas. Nothing
    here is more than `role` may read: no entity lists or statistics, and for an agent no
    session description (ours counts the targets and obstacles of the whole map)."""
    data = live.session.data
    width, height = (data.get("map_size_m") or [data.get("canvas_width", 1024),
                                                data.get("canvas_height", 768)])[:2]
    description = "" if role is Role.AGENT else data.get("description", "")
    return {"description": description, "creator": "system",
            "status": "active" if active else "inactive",
            "task_type": live.session.task_type,
            "task_description": live.task.text, "is_distance_3d": False,
            "canvas_width": width, "canvas_height": height,
            "created_at": live.started_wall_s, "last_updated": time.time()}
