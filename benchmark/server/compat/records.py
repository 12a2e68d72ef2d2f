"""MultiUAV-Plat's complete entity records (entities.md sections 3.2, 4.1 and 5): every field
the reference sends, from a session file's record, null where the world has no value for it
(a fixed target has no velocity, nobody here keeps a wall-clock motion update). One pydantic
model per record is the single definition of its fields; `full_record` fills a raw record in.

An obstacle's `area` is computed from its geometry (pi r^2 for a point or circle, pi w l for an
ellipse of semi-axes width and length, the shoelace area of a polygon)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from pydantic import BaseModel, ConfigDict
from shapely.geometry import Polygon

__all__ = ["EnvironmentRecord", "ObstacleRecord", "TargetRecord", "full_record",
           "obstacle_area_m2"]

_DEFAULT_RADIUS_M = 1.0
_STATION_CHARGE_PCT = 25.0
_MOVING_DURATION_S = 10.0


class _Record(BaseModel):
    model_config = ConfigDict(extra="allow")


class TargetRecord(_Record):
    """A target as the reference returns it."""

    id: str
    name: str
    type: str
    position: dict[str, float]
    description: str = ""
    radius: float = _DEFAULT_RADIUS_M
    vertices: list[dict[str, float]] | None = None
    velocity: dict[str, float] | None = None
    moving_path: list[dict[str, float]] | None = None
    moving_duration: float | None = None
    charge_amount: float | None = None
    current_path_index: int | None = None
    path_direction: int | None = None
    time_in_direction: float | None = None
    movement_mode: str | None = None
    calculated_speed: float | None = None
    last_motion_update: float | None = None
    last_tracked_at: float | None = None
    is_reached: bool | None = None
    reached_by: list[str] | None = None
    created_at: float | None = None
    last_updated: float | None = None


class ObstacleRecord(_Record):
    """An obstacle as the reference returns it."""

    id: str
    name: str
    type: str
    position: dict[str, float]
    description: str = ""
    radius: float | None = None
    width: float | None = None
    length: float | None = None
    vertices: list[dict[str, float]] | None = None
    height: float = 0.0
    area: float | None = None
    created_at: float | None = None
    last_updated: float | None = None


class EnvironmentRecord(_Record):
    """The environment as the reference returns it (its defaults where the file is silent)."""

    id: str | None = None
    name: str = "Default Environment"
    weather: str = "clear"
    temperature: float = 20.0
    humidity: float = 50.0
    pressure: float = 1013.25
    wind_speed: float = 0.0
    wind_direction: str = "north"
    visibility: float = 10000.0
    created_at: float | None = None
    last_updated: float | None = None


def obstacle_area_m2(record: Mapping[str, Any]) -> float | None:
    """The footprint's area of an obstacle record; None when its geometry is incomplete."""
    kind = record.get("type")
    try:
        if kind in ("point", "circle"):
            radius = float(record.get("radius") or _DEFAULT_RADIUS_M)
            return round(math.pi * radius * radius, 3)
        if kind == "ellipse":
            return round(math.pi * float(record["width"]) * float(record["length"]), 3)
        if kind == "polygon":
            ring = [(float(v["x"]), float(v["y"])) for v in record.get("vertices") or ()]
            return round(Polygon(ring).area, 3) if len(ring) >= 3 else None
    except (KeyError, TypeError, ValueError):
        return None
    return None


def _target(record: Mapping[str, Any]) -> dict[str, Any]:
    raw = dict(record)
    kind = raw.get("type")
    if kind == "waypoint" and raw.get("charge_amount") is None:
        raw["charge_amount"] = _STATION_CHARGE_PCT
    if kind == "moving":
        raw.setdefault("moving_duration", _MOVING_DURATION_S)
        velocity = raw.get("velocity") or {}
        moves = any(abs(float(velocity.get(a) or 0.0)) > 1e-9 for a in "xyz")
        raw.setdefault("movement_mode", "velocity" if moves else
                       "path" if len(raw.get("moving_path") or ()) >= 2 else "stationary")
        raw.setdefault("current_path_index", 0)
        raw.setdefault("path_direction", 1)
    else:
        raw.setdefault("movement_mode", "stationary")
    return TargetRecord.model_validate(raw).model_dump()


def _obstacle(record: Mapping[str, Any]) -> dict[str, Any]:
    raw = dict(record)
    if raw.get("type") == "point" and raw.get("radius") is None:
        raw["radius"] = _DEFAULT_RADIUS_M
    raw["area"] = obstacle_area_m2(raw)
    return ObstacleRecord.model_validate(raw).model_dump()


def full_record(kind: str, record: Mapping[str, Any]) -> dict[str, Any]:
    """`record` (of "targets", "obstacles" or "environment") with every field the reference
    sends; a record the model cannot read is returned as it is."""
    try:
        if kind == "targets":
            return _target(record)
        if kind == "obstacles":
            return _obstacle(record)
        if kind == "environment":
            return EnvironmentRecord.model_validate(dict(record)).model_dump()
    except ValueError:
        return dict(record)
    return dict(record)
