"""MultiUAV-Plat's collision checks, for planning a path before flying it.

`POST /obstacles/point_collision` with `{x, y, z?, margin = 0}` answers
`{result, inside_obstacle_ids, inside_obstacles: [{id, name, type, height,
distance_to_boundary}], point, margin, message}`: every obstacle holding the point.
`POST /obstacles/path_collision` with `{start: {x, y, z?}, end: {x, y, z?}, safety_margin = 1}`
answers the first obstacle along the segment, `{obstacle_id, obstacle_name, type,
collision_type, distance}` (distance: metres from the start to the first contact), or null.

The reference's rules (commands.md section 5): a point collides when it lies inside or on the
footprint grown by the margin and, when z is given, the obstacle has height 0 or z <= height
+ margin; a segment collides when its 2D line meets the grown footprint and the obstacle has
height 0 or the higher end is at most height + margin. Operators and admins check against the
whole map. An agent checks only against the obstacles its drones perceive now: an answer of
"no collision" means none that it knows of (the `X-Collision-Scope` header says which).
"""

from typing import Annotated, Any

import shapely
from fastapi import Depends, FastAPI, HTTPException, Query, Request, Response

from benchmark.server.auth import require
from benchmark.server.compat.commands import resolve_session
from benchmark.server.compat.world import perceived_ids
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from emulator.world import Obstacle
from llm_tools.input_limits import parse_json, parse_number, preview

__all__ = ["MAX_MARGIN_M", "add_compat_collision_routes"]

MAX_MARGIN_M = 10_000.0
SCOPE_HEADER = "X-Collision-Scope"


def _scope(live: LiveSession, caller: Caller) -> tuple[list[Obstacle], str]:
    obstacles = list(live.session.scenario.world.obstacles)
    if caller.role is not Role.AGENT:
        return obstacles, "map"
    seen = perceived_ids(live, "obstacles")
    return [o for o in obstacles if o.id in seen], "perceived"


def _object(body: Any, where: str, allowed: tuple[str, ...]) -> dict[str, Any]:
    if not isinstance(body, dict):
        raise HTTPException(422, f"{where} must be an object with {', '.join(allowed)}; got "
                            f"{preview(body)}")
    unknown = sorted(set(body) - set(allowed))
    if unknown:
        raise HTTPException(422, f"{where}: unknown field(s) {', '.join(map(preview, unknown))};"
                            f" fields: {', '.join(allowed)}")
    return body


def _number(body: dict[str, Any], key: str, where: str, default: float | None = None
            ) -> float | None:
    """body[key] as a number; `default` when absent (None: optional)."""
    if body.get(key) is None:
        return default
    return parse_number(body[key], f"{where}{key}")


def _xy(body: dict[str, Any], where: str) -> tuple[float, float]:
    for key in ("x", "y"):
        if body.get(key) is None:
            raise HTTPException(422, f"{where}{key} is required (a number)")
    return parse_number(body["x"], f"{where}x"), parse_number(body["y"], f"{where}y")


def _margin(body: dict[str, Any], key: str, default: float) -> float:
    value = _number(body, key, "", default)
    assert value is not None
    if not 0.0 <= value <= MAX_MARGIN_M:
        raise HTTPException(422, f"{key} is {value:g}; it must lie in [0, {MAX_MARGIN_M:g}] m")
    return value


def _grown(obstacle: Obstacle, margin_m: float) -> shapely.Polygon:
    return obstacle.footprint if margin_m == 0.0 else shapely.buffer(obstacle.footprint,
                                                                     margin_m)


def _blocks(obstacle: Obstacle, z_m: float | None, margin_m: float) -> bool:
    return z_m is None or obstacle.height_m == 0.0 or z_m <= obstacle.height_m + margin_m


def point_collision(obstacles: list[Obstacle], scope: str, body: Any) -> dict[str, Any]:
    body = _object(body, "the body", ("x", "y", "z", "margin"))
    x, y = _xy(body, "")
    z = _number(body, "z", "")
    margin = _margin(body, "margin", 0.0)
    inside: list[dict[str, Any]] = []
    for obstacle in obstacles:
        area = _grown(obstacle, margin)
        if _blocks(obstacle, z, margin) and shapely.intersects_xy(area, x, y):
            depth = float(area.exterior.distance(shapely.Point(x, y)))
            inside.append({"id": obstacle.id, "name": obstacle.name, "type": obstacle.kind,
                           "height": obstacle.height_m,
                           "distance_to_boundary": round(-depth, 3) if depth else 0.0})
    point = {"x": x, "y": y} if z is None else {"x": x, "y": y, "z": z}
    known = "the map's" if scope == "map" else "the perceived"
    message = (f"point is inside {len(inside)} of {known} obstacles: "
               f"{', '.join(str(o['name']) for o in inside)}" if inside
               else f"point is clear of {known} obstacles ({len(obstacles)})")
    return {"result": bool(inside), "inside_obstacle_ids": [o["id"] for o in inside],
            "inside_obstacles": inside, "point": point, "margin": margin, "message": message}


def _end(body: dict[str, Any], key: str) -> tuple[float, float, float]:
    raw = body.get(key)
    if raw is None:
        raise HTTPException(422, f"{key} is required: {{x, y[, z]}}")
    point = _object(raw, key, ("x", "y", "z"))
    x, y = _xy(point, f"{key}.")
    z = _number(point, "z", f"{key}.", 0.0)
    assert z is not None
    return x, y, z


def path_collision(obstacles: list[Obstacle], body: Any) -> dict[str, Any] | None:
    body = _object(body, "the body", ("start", "end", "safety_margin"))
    (x0, y0, z0), (x1, y1, z1) = _end(body, "start"), _end(body, "end")
    margin = _margin(body, "safety_margin", 1.0)
    start = shapely.Point(x0, y0)
    line = start if (x0, y0) == (x1, y1) else shapely.LineString([(x0, y0), (x1, y1)])
    first: tuple[float, Obstacle] | None = None
    for obstacle in obstacles:
        area = _grown(obstacle, margin)
        if not _blocks(obstacle, max(z0, z1), margin) or not area.intersects(line):
            continue
        distance = float(start.distance(area.intersection(line)))
        if first is None or distance < first[0]:
            first = (distance, obstacle)
    if first is None:
        return None
    distance, obstacle = first
    kind = "start_inside" if shapely.intersects_xy(_grown(obstacle, margin), x0, y0) \
        else "path_intersection"
    return {"obstacle_id": obstacle.id, "obstacle_name": obstacle.name, "type": obstacle.kind,
            "collision_type": kind, "distance": round(distance, 3)}


def add_compat_collision_routes(app: FastAPI, hub: Hub) -> None:
    anyone = require(hub, Role.AGENT, Role.OPERATOR, Role.ADMIN)
    pick = Query(None, description="session id (operator and admin keys)")

    @app.post("/obstacles/point_collision", tags=["multiuav-plat"],
              summary="Obstacles holding a point (an agent: among those it perceives)")
    async def point(request: Request, response: Response,
                    caller: Annotated[Caller, Depends(anyone)], session: str | None = pick
                    ) -> dict[str, Any]:
        obstacles, scope = _scope(resolve_session(hub, caller, session), caller)
        response.headers[SCOPE_HEADER] = scope
        return point_collision(obstacles, scope, parse_json(await request.body()))

    @app.post("/obstacles/path_collision", tags=["multiuav-plat"],
              summary="The first obstacle on a straight segment, or null (an agent: among "
                      "those it perceives)")
    async def path(request: Request, response: Response,
                   caller: Annotated[Caller, Depends(anyone)], session: str | None = pick
                   ) -> dict[str, Any] | None:
        obstacles, scope = _scope(resolve_session(hub, caller, session), caller)
        response.headers[SCOPE_HEADER] = scope
        return path_collision(obstacles, parse_json(await request.body()))
