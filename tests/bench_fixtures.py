"""Helpers for the benchmark tests: small generated sessions written to a temporary folder.

Not a conftest: test modules import what they use.
"""

from __future__ import annotations

import json
import random
from pathlib import Path
from typing import Any

from benchmark.authoring.generate import build_task
from benchmark.authoring.scenarios import generate_world
from benchmark.authoring.session_file import dump_session, session_from_dict
from benchmark.authoring.templates import SessionView, template

__all__ = ["reference_session", "small_session", "write_json"]


def small_session(keys: list[str], *, family: str = "area_search", index: int = 1,
                  seed: int = 7) -> dict[str, Any]:
    """An easy generated world with one task per template key, in that order."""
    world = generate_world(family, "easy", index)
    scenario = session_from_dict({**world, "tasks": []}).scenario
    w, h = world["map_size_m"]
    view = SessionView(family, scenario, float(w), float(h))
    tasks = [build_task(template(key), view, random.Random(f"{seed}/{k}"), f"t{k + 1:02d}")
             for k, key in enumerate(keys)]
    return {**world, "tasks": tasks}


def overcrowded(data: dict[str, Any]) -> dict[str, Any]:
    """The session with 251 drones where its first one stands: it loads, but no swarm can
    start it (MAVLink system ids end at 250)."""
    first = data["drones"][0]
    drones = [{**first, "id": f"crowd{k:03d}", "name": f"Crowd {k}"} for k in range(251)]
    return {**data, "drones": drones}


def write_json(path: Path, data: Any) -> Path:
    path.write_text(dump_session(data) if isinstance(data, dict) else json.dumps(data))
    return path


def reference_session() -> dict[str, Any]:
    """A small session in the MultiUAV-Plat export layout (no mavswarm keys), with no tasks."""
    drones = [{"id": f"a{k}b{k}c{k}d{k}", "name": f"Drone {k}", "model": "Model-A",
               "status": "idle", "position": {"x": 40.0 + 12 * k, "y": 50.0, "z": 0.0},
               "max_speed": 15, "max_altitude": 300, "battery_capacity": 80.0}
              for k in range(1, 5)]
    targets = [
        {"id": "1a2b3c4d", "name": "Circle Target 1", "type": "circle",
         "position": {"x": 300.0, "y": 260.0, "z": 0.0}, "radius": 40},
        {"id": "5e6f7a8b", "name": "Fixed Target 1", "type": "fixed",
         "position": {"x": 150.0, "y": 400.0, "z": 0.0}, "radius": 8},
        {"id": "9c0d1e2f", "name": "Waypoint 1", "type": "waypoint",
         "position": {"x": 90.0, "y": 160.0, "z": 0.0}, "radius": 10, "charge_amount": 30.0},
    ]
    obstacles = [
        {"id": "0f1e2d3c", "name": "Circle Obstacle 1", "type": "circle",
         "position": {"x": 220.0, "y": 120.0, "z": 0.0}, "radius": 20, "height": 0.0},
        {"id": "4b5a6978", "name": "Polygon Obstacle 1", "type": "polygon",
         "position": {"x": 430.0, "y": 420.0, "z": 0.0}, "height": 0.0,
         "vertices": [{"x": 410.0, "y": 400.0}, {"x": 450.0, "y": 400.0},
                      {"x": 450.0, "y": 440.0}, {"x": 410.0, "y": 440.0}]},
    ]
    return {"id": "feedc0de", "name": "Reference Area Search", "description": "",
            "status": "inactive", "task_type": "area_search", "canvas_width": 1024,
            "canvas_height": 768, "drones": drones, "targets": targets,
            "obstacles": obstacles,
            "environment": {"name": "Env", "weather": "clear", "wind_speed": 2.5,
                            "wind_direction": "east"},
            "tasks": [], "history": {}}
