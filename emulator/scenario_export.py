"""A scenario written back in the session-file entity layout (the inverse of
`emulator.scenario.scenario_from_dict`): what views draw and what an exported truth record
carries so that a replay shows the world it was flown in."""

from __future__ import annotations

from typing import Any

from emulator.scenario import CHARGE_AMOUNT_PERIOD_S, Scenario
from emulator.world import Obstacle, Target

__all__ = ["scenario_to_dict"]


def _xyz(p: tuple[float, ...]) -> dict[str, float]:
    return {"x": round(p[0], 3), "y": round(p[1], 3), "z": round(p[2] if len(p) > 2 else 0.0, 3)}


def _vertices(polygon: Any) -> list[dict[str, float]]:
    coords = list(polygon.exterior.coords)[:-1]
    return [{"x": round(x, 3), "y": round(y, 3)} for x, y in coords]


def _half_extent(polygon: Any) -> tuple[float, float]:
    x0, y0, x1, y1 = polygon.bounds
    return round((x1 - x0) / 2.0, 3), round((y1 - y0) / 2.0, 3)


def _obstacle(o: Obstacle) -> dict[str, Any]:
    out: dict[str, Any] = {"id": o.id, "name": o.name, "type": o.kind,
                           "height": round(o.height_m, 3)}
    if o.kind == "polygon":
        out["vertices"] = _vertices(o.footprint)
        return out
    out["position"] = _xyz((*o.center_m, 0.0))
    rx, ry = _half_extent(o.footprint)
    if o.kind == "ellipse":
        out["width"], out["length"] = rx, ry
    else:
        out["radius"] = rx
    return out


def _target(t: Target) -> dict[str, Any]:
    out: dict[str, Any] = {"id": t.id, "name": t.name, "type": t.kind}
    if t.kind == "polygon":
        out["vertices"] = _vertices(t.geometry)
        out["radius"] = t.radius_m
        return out
    out["position"] = _xyz(t.position_m)
    out["radius"] = t.radius_m
    if t.charge_rate_pct_s is not None:
        out["charge_amount"] = round(t.charge_rate_pct_s * CHARGE_AMOUNT_PERIOD_S, 3)
    return out


def scenario_to_dict(scenario: Scenario) -> dict[str, Any]:
    """The scenario's world and vehicles as a session-file object (no tasks)."""
    world = scenario.world
    drones = [{"id": v.id, "name": v.name, "model": v.model, "position": _xyz(v.position_m),
               "heading": v.heading_deg, "home_position": _xyz(v.home_m),
               "max_speed": v.max_speed_m_s, "max_altitude": v.max_altitude_m,
               "perceived_radius": v.perceived_radius_m, "task_radius": v.task_radius_m,
               "battery_level": v.battery_pct, "battery_capacity": v.battery_capacity_mah,
               **({"gimbal": True} if v.gimbal else {})}
              for v in scenario.vehicles]
    return {"name": scenario.name, "task_type": scenario.task_type,
            "safety_margin_m": world.safety_margin_m,
            "origin": {"latitude_deg": world.origin.latitude_deg,
                       "longitude_deg": world.origin.longitude_deg,
                       "altitude_amsl_m": world.origin.altitude_amsl_m},
            "environment": {"wind_speed": world.wind.speed_m_s,
                            "wind_direction": world.wind.from_direction_deg},
            "drones": drones, "targets": [_target(t) for t in world.targets],
            "obstacles": [_obstacle(o) for o in world.obstacles]}
