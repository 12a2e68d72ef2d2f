"""MultiUAV-Plat's session screenshot: a PNG of the 2D map (obstacles dark grey, area targets
light green, point targets green, charging stations blue, drones red with their perception
circle), north up, rendered on the server from the world's geometry with shapely and written
with zlib (no imaging library). It shows the whole map, so it is for operators and admins
only (`GET /sessions/current/screenshot`, `GET /sessions/{id}/screenshot`); an agent's key is
refused (the reference gives it to agents: a map leak, perception_and_roles.md section 3).

Query: `width` (pixels, 64-2048, default 800); the height follows the map's aspect.
Formats other than png are 422."""

import struct
import zlib
from typing import Annotated, Literal

import numpy as np
import shapely
from fastapi import Depends, FastAPI, Query
from fastapi.responses import Response

from benchmark.server.auth import live_session, require
from benchmark.server.compat.commands import resolve_session
from benchmark.server.hub import Caller, Hub, LiveSession, Role

__all__ = ["add_compat_screenshot_routes", "png_bytes", "render_map"]

BACKGROUND = (248, 248, 244)
OBSTACLE = (90, 90, 90)
AREA = (200, 235, 200)
POINT = (40, 150, 60)
STATION = (60, 110, 210)
DRONE = (210, 40, 40)
SENSOR = (240, 190, 190)
DRONE_DOT_PX = 4.0


def png_bytes(rgb: np.ndarray) -> bytes:
    """An (h, w, 3) uint8 image as PNG bytes (8-bit RGB, filter 0 on every row)."""
    height, width, _ = rgb.shape

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    rows = np.concatenate([np.zeros((height, 1), np.uint8),
                           rgb.astype(np.uint8).reshape(height, width * 3)], axis=1)
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
            + chunk(b"IDAT", zlib.compress(rows.tobytes(), 6)) + chunk(b"IEND", b""))


def _bounds(live: LiveSession) -> tuple[float, float, float, float]:
    """The map's extent: its canvas from the origin, grown to hold everything on it."""
    data = live.session.data
    size = data.get("map_size_m") or [data.get("canvas_width", 1024),
                                      data.get("canvas_height", 768)]
    x0, y0, x1, y1 = 0.0, 0.0, float(size[0]), float(size[1])
    world = live.session.scenario.world
    shapes = [o.footprint for o in world.obstacles] + [t.geometry for t in world.targets]
    points = [(s.x_m, s.y_m) for s in live.gateway.list_drones()]
    if shapes:
        bx0, by0, bx1, by1 = shapely.total_bounds(shapes).tolist()
        x0, y0, x1, y1 = min(x0, bx0), min(y0, by0), max(x1, bx1), max(y1, by1)
    for x, y in points:
        x0, y0, x1, y1 = min(x0, x - 10), min(y0, y - 10), max(x1, x + 10), max(y1, y + 10)
    return x0, y0, x1, y1


def render_map(live: LiveSession, width_px: int) -> np.ndarray:
    """The session's 2D map now as an (h, w, 3) image, north up."""
    x0, y0, x1, y1 = _bounds(live)
    scale = width_px / max(x1 - x0, 1e-6)
    height_px = max(1, min(4096, round((y1 - y0) * scale)))
    xs = x0 + (np.arange(width_px) + 0.5) / scale
    ys = y1 - (np.arange(height_px) + 0.5) / scale  # row 0 is the north edge
    gx, gy = np.meshgrid(xs, ys)
    image = np.empty((height_px, width_px, 3), np.uint8)
    image[:] = BACKGROUND
    world = live.session.scenario.world
    states = live.gateway.list_drones()
    radius = {v.id: v.perceived_radius_m for v in live.session.scenario.vehicles}
    for state in states:
        ring = np.hypot(gx - state.x_m, gy - state.y_m)
        r = radius.get(state.drone, 0.0)
        image[np.abs(ring - r) <= 0.75 / scale] = SENSOR
    for target in world.targets:
        colour = (AREA if target.is_area else STATION if target.is_charging_station
                  else POINT)
        image[shapely.contains_xy(target.geometry, gx, gy)] = colour
    for obstacle in world.obstacles:
        image[shapely.contains_xy(obstacle.footprint, gx, gy)] = OBSTACLE
    for state in states:
        image[np.hypot(gx - state.x_m, gy - state.y_m) <= DRONE_DOT_PX / scale] = DRONE
    return image


def add_compat_screenshot_routes(app: FastAPI, hub: Hub) -> None:
    staff = require(hub, Role.OPERATOR, Role.ADMIN)
    pick = Query(None, description="session id (operator and admin keys)")
    width = Query(800, ge=64, le=2048, description="image width in pixels")
    kind = Query("png", description="image format (png only)")

    @app.get("/sessions/current/screenshot", tags=["multiuav-plat"],
             summary="A PNG of the current session's 2D map (operator, admin)",
             response_class=Response)
    def current(caller: Annotated[Caller, Depends(staff)], session: str | None = pick,
                width: int = width, format: Literal["png"] = kind) -> Response:
        live = resolve_session(hub, caller, session)
        return Response(png_bytes(render_map(live, width)), media_type="image/png")

    @app.get("/sessions/{session_id}/screenshot", tags=["multiuav-plat"],
             summary="A PNG of a session's 2D map (operator, admin)", response_class=Response)
    def of_session(session_id: str, caller: Annotated[Caller, Depends(staff)],
                   width: int = width, format: Literal["png"] = kind) -> Response:
        live = live_session(hub, caller, session_id)
        return Response(png_bytes(render_map(live, width)), media_type="image/png")
