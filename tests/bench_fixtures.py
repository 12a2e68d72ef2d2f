"""Helpers for the benchmark tests: small generated sessions written to a temporary folder.

Not a conftest: test modules import what they use.
"""

from __future__ import annotations

import json
import random
from pathlib import Path
from typing import Any

from benchmark.generate import build_task
from benchmark.scenarios import generate_world
from benchmark.session_file import dump_session, session_from_dict
from benchmark.templates import SessionView, template

__all__ = ["small_session", "write_json"]


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


def write_json(path: Path, data: Any) -> Path:
    path.write_text(dump_session(data) if isinstance(data, dict) else json.dumps(data))
    return path
