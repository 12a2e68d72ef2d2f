"""The scenario editor's server half: a blank map, an existing session file or a generated
level to start from, and validation and saving of what the page edited. A session is saved
only when it loads exactly as `mavswarm up` and `bench run` will load it; otherwise the problem
is answered, naming the entity (`drones[2]`, ...) so the page can mark it, and nothing is
written.

Session files are opened from the server's session folders only
(benchmark.authoring.session_folders; the route reads them), or uploaded in a request's body; either
way `editable_session` turns the parsed JSON into what the page edits.
"""

from __future__ import annotations

import math
import os
import re
import stat
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from benchmark.authoring.importer import import_session
from benchmark.authoring.scenarios import FAMILIES, LEVELS, SESSION_INDICES
from benchmark.authoring.scenarios.generator import generate_world
from benchmark.authoring.session_file import (
    SCHEMA,
    SessionFileError,
    dump_session,
    session_from_dict,
)
from console.shipped import edited_id, shipped_ids

__all__ = ["EditorError", "blank_session", "editable_session", "generated_session",
           "save_session", "start_choices", "validate_session", "write_in_folder"]

MIN_DRONE_SPACING_M = 1.0
_ENTITY = re.compile(r"\b(drones|targets|obstacles|tasks)\[(\d+)\]")


class EditorError(ValueError):
    """A session the editor refuses; `entity` is ("drones", 2) when one is to blame."""

    def __init__(self, message: str) -> None:
        super().__init__(message)
        found = _ENTITY.search(message)
        self.entity = (found.group(1), int(found.group(2))) if found else None

    def to_json(self) -> dict[str, Any]:
        where = None if self.entity is None else {"list": self.entity[0],
                                                  "index": self.entity[1]}
        return {"ok": False, "error": str(self), "entity": where}


def blank_session(width_m: float = 600.0, height_m: float = 600.0) -> dict[str, Any]:
    """An empty map with one drone, ready to edit."""
    return {"schema": SCHEMA, "id": "custom-1", "family": "custom", "level": "custom",
            "index": 0, "name": "Custom session", "description": "", "task_type": "others",
            "map_size_m": [width_m, height_m], "safety_margin_m": 2.0,
            "drones": [{"id": "d1", "name": "Drone 1", "position": {"x": 20.0, "y": 20.0,
                                                                    "z": 0.0},
                        "max_speed": 15, "max_altitude": 120, "battery_capacity": 5000}],
            "targets": [], "obstacles": [], "tasks": []}


def start_choices() -> dict[str, Any]:
    """What a generated level to start from is picked among: the benchmark's families
    (benchmark.authoring.scenarios.families), levels and session indices."""
    return {"families": list(FAMILIES), "levels": list(LEVELS),
            "indices": list(SESSION_INDICES)}


def generated_session(family: str, level: str, index: int) -> dict[str, Any]:
    """A generated level's world (no tasks) as a session to edit."""
    world: dict[str, Any] = dict(generate_world(family, level, index))
    world.setdefault("schema", SCHEMA)
    world["tasks"] = []
    return world


def editable_session(data: Any, source: str) -> dict[str, Any]:
    """A session file's parsed JSON as the editor edits it: a mavswarm session as it is (to
    fix what is wrong in it), a MultiUAV-Plat one converted as `bench import` does. Raises
    ValueError (SessionFileError, SessionImportError) naming `source` and the field."""
    if isinstance(data, Mapping) and data.get("schema") == SCHEMA:
        return dict(data)
    if isinstance(data, Mapping) and data.get("schema") is None and "drones" in data:
        converted, _ = import_session(data, source=source)
        return converted
    return dict(session_from_dict(data, source=source).data)


def _check_spacing(data: Mapping[str, Any]) -> None:
    spots: list[tuple[float, float, float]] = []
    for k, drone in enumerate(data.get("drones") or []):
        p = drone.get("position") if isinstance(drone, Mapping) else None
        if not isinstance(p, Mapping):
            continue
        try:
            here = (float(p.get("x", 0.0)), float(p.get("y", 0.0)), float(p.get("z", 0.0)))
        except (TypeError, ValueError):
            continue
        for j, other in enumerate(spots):
            if math.dist(here, other) < MIN_DRONE_SPACING_M:
                raise EditorError(f"drones[{k}]: overlaps drones[{j}] (closer than "
                                  f"{MIN_DRONE_SPACING_M:g} m)")
        spots.append(here)


def validate_session(data: Any) -> dict[str, Any]:
    """A summary of a valid session; raises EditorError naming what is wrong."""
    if not isinstance(data, Mapping):
        raise EditorError("the session must be a JSON object")
    _check_spacing(data)
    try:
        session = session_from_dict(data, source="session")
    except SessionFileError as error:
        raise EditorError(str(error)) from None
    for k, task in enumerate(session.tasks):
        if task.error is not None:
            raise EditorError(f"tasks[{k}] ({task.id}): {task.error}")
    return {"ok": True, "id": session.id, "drones": len(session.scenario.vehicles),
            "targets": len(session.scenario.world.targets),
            "obstacles": len(session.scenario.world.obstacles), "tasks": len(session.tasks),
            "notes": list(session.scenario.notes)}


def save_session(data: Any, path: Path, root: Path) -> dict[str, Any]:
    """Validate, then write `data` to `path` (inside `root`, ending in .json)."""
    summary = validate_session(data)
    if summary["id"] in shipped_ids():
        raise EditorError(f"session id {summary['id']!r} is a shipped session's: save the edited "
                          f"copy under a new id (e.g. {edited_id(summary['id'])!r}) so its "
                          "results never mix with the shipped session's")
    target = write_in_folder(dump_session(data), path, root)
    return {**summary, "path": str(target)}


def write_in_folder(text: str, path: Path, root: Path) -> Path:
    """Write `text` to `path` (relative to `root`, or absolute inside it; ending in .json;
    never over anything but a regular file), replacing it whole; the path written."""
    target = (root / path).resolve() if not path.is_absolute() else path.resolve()
    if not target.is_relative_to(root.resolve()):
        raise EditorError(f"{path}: files are saved under {root}")
    if target.suffix != ".json":
        raise EditorError(f"{path}: a file name here ends in .json")
    try:
        if os.path.lexists(target) and not stat.S_ISREG(os.lstat(target).st_mode):
            raise EditorError(f"{path}: exists and is not a regular file; pick another name")
        target.parent.mkdir(parents=True, exist_ok=True)
        _write_replacing(target, text)
    except OSError as error:
        raise EditorError(f"{path}: cannot save there: {error.strerror}") from None
    return target


def _write_replacing(target: Path, text: str) -> None:
    """Write `text` to a new file beside `target`, then move it over `target`: a reader never
    sees half a file, and nothing is opened at `target` itself."""
    fd, temporary = tempfile.mkstemp(dir=target.parent, prefix=".editor-", suffix=".json")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as file:
            file.write(text)
        os.chmod(temporary, 0o644)
        os.replace(temporary, target)
    except BaseException:
        os.unlink(temporary)
        raise
