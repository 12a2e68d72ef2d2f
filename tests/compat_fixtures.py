"""A MultiUAV-Plat world served the way `mavswarm serve --open` serves it (live_hub: a stepped
swarm per session, an operator can load more), reached in-process over httpx; and a client that
knows only the reference's documented routes and fields."""

from __future__ import annotations

import contextlib
import copy
from collections.abc import AsyncIterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx

from benchmark.server import Hub, Role, create_app
from benchmark.server.serve import live_hub
from tests.bench_fixtures import write_json

__all__ = ["KEYS", "PlatClient", "Served", "plat_server", "plat_world"]

KEYS = {"agent": "plat-agent", "operator": "plat-operator", "admin": "plat-admin"}

_WORLD: dict[str, Any] = {
    "id": "c0ffee01", "name": "Compat Patrol", "description": "A small patrol world",
    "status": "inactive", "task_type": "target_assignment", "canvas_width": 600,
    "canvas_height": 500,
    "drones": [
        {"id": "d1d1d1d1", "name": "Drone 1", "model": "Model-A", "status": "idle",
         "position": {"x": 100.0, "y": 100.0, "z": 0.0}, "max_speed": 15,
         "max_altitude": 200, "battery_capacity": 80.0, "perceived_radius": 60,
         "task_radius": 10},
        {"id": "d2d2d2d2", "name": "Drone 2", "model": "Model-X1", "status": "idle",
         "position": {"x": 130.0, "y": 100.0, "z": 0.0}, "max_speed": 12,
         "max_altitude": 150, "battery_capacity": 90.0, "perceived_radius": 60,
         "task_radius": 10},
    ],
    "targets": [
        {"id": "f1f1f1f1", "name": "Fixed Target 1", "type": "fixed",
         "position": {"x": 100.0, "y": 160.0, "z": 0.0}, "radius": 3},
        {"id": "a1a1a1a1", "name": "Waypoint 1", "type": "waypoint",
         "position": {"x": 130.0, "y": 100.0, "z": 0.0}, "radius": 10, "charge_amount": 30.0},
        {"id": "c1c1c1c1", "name": "Circle Target 1", "type": "circle",
         "position": {"x": 400.0, "y": 350.0, "z": 0.0}, "radius": 30},
    ],
    "obstacles": [
        {"id": "0b0b0b01", "name": "Circle Obstacle 1", "type": "circle",
         "position": {"x": 100.0, "y": 220.0, "z": 0.0}, "radius": 10, "height": 0.0},
        {"id": "0b0b0b02", "name": "Polygon Obstacle 1", "type": "polygon",
         "position": {"x": 430.0, "y": 130.0, "z": 0.0}, "height": 20.0,
         "vertices": [{"x": 410.0, "y": 110.0}, {"x": 450.0, "y": 110.0},
                      {"x": 450.0, "y": 150.0}, {"x": 410.0, "y": 150.0}]},
    ],
    "environment": {"id": "e0e0e0e0", "name": "Calm", "weather": "clear", "temperature": 20.0,
                    "humidity": 50.0, "wind_speed": 0.0, "wind_direction": "north"},
    "tasks": [{
        "id": "7a5k0001", "name": "photo_patrol",
        "content": "Take off Drone 1 to 12 m, fly to Fixed Target 1, take a photo of it and "
                   "land.",
        "execution_check_apis": {"logic": "and", "checks": [
            {"endpoint": "/check/drone_has_taken_off",
             "parameters": {"drone_id": "d1d1d1d1", "min_altitude": 10.0}},
            {"endpoint": "/check/target_is_reached_by_drone",
             "parameters": {"target_id": "f1f1f1f1", "drone_id": "d1d1d1d1"}},
            {"endpoint": "/check/target_in_photo_taken_by_drone",
             "parameters": {"drone_id": "d1d1d1d1", "target_id": "f1f1f1f1"}},
            {"endpoint": "/check/drone_has_landed", "parameters": {"drone_id": "d1d1d1d1"}},
        ]}}],
    "history": {},
}


def plat_world() -> dict[str, Any]:
    """A MultiUAV-Plat session file (the reference's export layout) with one task: two
    drones, a fixed target 60 m north of Drone 1, a charging station under Drone 2, an area
    target and two obstacles out of every drone's reach at the start."""
    return copy.deepcopy(_WORLD)


@dataclass
class Served:
    client: httpx.AsyncClient
    hub: Hub
    path: Path


@contextlib.asynccontextmanager
async def plat_server(tmp_path: Path, data: dict[str, Any] | None = None
                      ) -> AsyncIterator[Served]:
    """`mavswarm serve --sessions <file> --open` with an agent, operator and admin key."""
    path = write_json(tmp_path / "plat_world.json", data or plat_world())
    async with live_hub([path]) as hub:
        hub.open_access = True
        (session_id,) = hub.sessions
        for role, key in KEYS.items():
            hub.add_key(key, Role(role), session_id if role == "agent" else None)
        transport = httpx.ASGITransport(app=create_app(hub))
        async with httpx.AsyncClient(transport=transport, base_url="http://plat",
                                     timeout=120.0) as client:
            yield Served(client, hub, path)


class PlatClient:
    """A client written against the reference's API documentation: no key (the agent role) or
    an X-API-Key, query parameters for scalar command arguments, JSON bodies otherwise."""

    def __init__(self, http: httpx.AsyncClient, key: str | None = None) -> None:
        self.http = http
        self.headers = {"X-API-Key": key} if key else {}

    async def get(self, path: str, **params: Any) -> Any:
        response = await self.http.get(path, params=params, headers=self.headers)
        assert response.status_code == 200, (path, response.status_code, response.text)
        return response.json()

    async def post(self, path: str, body: Any = None, **params: Any) -> Any:
        response = await self.http.post(path, params=params, json=body, headers=self.headers)
        assert response.status_code == 200, (path, response.status_code, response.text)
        return response.json()

    async def command(self, drone: str, name: str, body: Any = None, **params: Any
                      ) -> dict[str, Any]:
        answer: dict[str, Any] = await self.post(f"/drones/{drone}/command/{name}", body,
                                                 **params)
        assert {"command_id", "drone_id", "command", "status", "message"} <= set(answer)
        assert answer["status"] in ("success", "partial_success", "error"), answer
        return answer
