"""The entities of a session file (MultiUAV-Plat format) as pydantic models
(`emulator.scenario_errors` turns their validation errors into messages naming the entity and
the field).

The models are the file's shape and its field rules (types, ranges, defaults, polygons, a
drone's altitudes); `emulator.scenario` builds a world from them (the reference mappings, ids
by position, uniqueness and placement). They are lenient where the reference is: unknown
fields are ignored, and a field given as ``null`` counts as absent (its default applies, or
it is reported as required). Numbers are JSON numbers (not strings, not booleans) and finite.
The JSON Schema of a scenario file (`scenario.schema.json` beside this module) is generated
from `ScenarioFile`: ``python -m emulator.scenario_model`` rewrites it.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
import shapely
from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    GetPydanticSchema,
    PlainValidator,
    WithJsonSchema,
    model_validator,
)
from pydantic.dataclasses import dataclass as pydantic_dataclass
from pydantic_core import PydanticCustomError, core_schema

from emulator.geo import GeoOrigin
from emulator.scenario_errors import show

__all__ = [
    "DEFAULT_MODEL", "SCHEMA_PATH", "WIND_DIRECTIONS_DEG", "DroneEntity", "EnvironmentEntity",
    "ObstacleEntity", "OriginEntity", "PointEntity", "ScenarioFile", "TargetEntity",
    "json_schema", "schema_text",
]

DEFAULT_MODEL = "generic-quad"
DEFAULT_PERCEIVED_RADIUS_M = 50.0
DEFAULT_TASK_RADIUS_M = 20.0
DEFAULT_TARGET_RADIUS_M = 1.0
DEFAULT_POINT_OBSTACLE_RADIUS_M = 1.0
DEFAULT_OBSTACLE_HEIGHT_M = 10.0
DEFAULT_CHARGE_AMOUNT_PCT = 25.0
WIND_DIRECTIONS_DEG = {"north": 0.0, "northeast": 45.0, "east": 90.0, "southeast": 135.0,
                       "south": 180.0, "southwest": 225.0, "west": 270.0, "northwest": 315.0}

Number = Annotated[float, Field(strict=True, allow_inf_nan=False)]
Positive = Annotated[float, Field(strict=True, allow_inf_nan=False, gt=0.0)]
NonNegative = Annotated[float, Field(strict=True, allow_inf_nan=False, ge=0.0)]
_NON_EMPTY = GetPydanticSchema(lambda tp, handler: core_schema.custom_error_schema(
    handler(tp), custom_error_type="non_empty_string",
    custom_error_message="must be a non-empty string"))
Text = Annotated[str, Field(strict=True, pattern=r"\S"), _NON_EMPTY]
Ident = Annotated[str, Field(strict=True, min_length=1), _NON_EMPTY]


def _null_means_absent(schema: dict[str, Any]) -> None:
    """JSON Schema: every optional property also takes null (read as absent)."""
    required = set(schema.get("required", ()))
    for name, prop in schema.get("properties", {}).items():
        options = prop.get("anyOf", [])
        if name in required or {"type": "null"} in options:
            continue
        keep = {k: prop.pop(k) for k in ("default", "description", "title") if k in prop}
        inner = prop.copy()
        prop.clear()
        prop.update(keep, anyOf=[*options] if options else [inner])
        prop["anyOf"].append({"type": "null"})


class _Entity(BaseModel):
    """An object of the file: unknown fields are ignored, a null field is absent."""

    model_config = ConfigDict(extra="ignore", json_schema_extra=_null_means_absent)

    @model_validator(mode="before")
    @classmethod
    def _drop_nulls(cls, data: Any) -> Any:
        if isinstance(data, dict) and None in data.values():
            return {k: v for k, v in data.items() if v is not None}
        return data


@pydantic_dataclass(frozen=True, slots=True, config=ConfigDict(extra="ignore"))
class PointEntity:
    """A position in local ENU metres (x east, y north, z up; z defaults to 0)."""

    x: Number
    y: Number
    z: Number | None = None

    def xyz(self) -> tuple[float, float, float]:
        return self.x, self.y, 0.0 if self.z is None else self.z


def _problem(kind: str, message: str, **ctx: Any) -> PydanticCustomError:
    """A validation error whose message is `message` as written."""
    return PydanticCustomError(kind, "{message}", {"message": message, **ctx})


def _field_error(field: str, message: str) -> PydanticCustomError:
    """An error about one field of the model being validated (`describe_error` adds the
    field to the location)."""
    return _problem("entity_field", message, field=field)


def _polygon(points: list[PointEntity]) -> list[PointEntity]:
    """Vertices normalised as the reference does: a closing duplicate is dropped."""
    if len(points) >= 2 and (points[-1].x, points[-1].y) == (points[0].x, points[0].y):
        points = points[:-1]
    if len(points) < 3:
        raise _problem("polygon", f"must have at least 3 vertices, got {len(points)}")
    polygon = shapely.Polygon([(p.x, p.y) for p in points])
    if not polygon.is_valid:
        raise _problem("polygon",
                       f"must form a valid polygon ({shapely.is_valid_reason(polygon)})")
    if polygon.area <= 1e-9:
        raise _problem("polygon", f"must enclose an area > 1e-9 m^2, got {polygon.area:g}")
    return points


Polygon = Annotated[list[PointEntity], AfterValidator(_polygon),
                    Field(description="at least 3 vertices {x, y} forming a simple polygon "
                                      "(a closing duplicate of the first is dropped)")]


def rounded_mean(points: list[PointEntity]) -> tuple[float, float, float]:
    """The reference's position of a polygon: the vertex mean rounded to whole metres."""
    xy = np.array([(p.x, p.y) for p in points])
    return float(round(xy[:, 0].mean())), float(round(xy[:, 1].mean())), points[0].xyz()[2]


class DroneEntity(_Entity):
    """A drone: its limits, where it starts and where its home is."""

    id: Ident | None = Field(None, description="default d1, d2, ... by position in the list")
    name: Text
    model: Text = DEFAULT_MODEL
    max_speed: Positive = Field(description="m/s (flown within MPC_XY_VEL_MAX's range)")
    max_altitude: Positive = Field(description="m (flown within GF_MAX_VER_DIST's range)")
    battery_capacity: Positive = Field(description="mAh; below 100 a MultiUAV-Plat size "
                                                   "label, x 100 mAh")
    position: PointEntity = Field(default_factory=lambda: PointEntity(x=0.0, y=0.0),
                                  description="where it starts; z between 0 and max_altitude")
    home_position: PointEntity | None = Field(None, description="default: position; home is "
                                                                "on the ground (z = 0)")
    perceived_radius: Positive = DEFAULT_PERCEIVED_RADIUS_M
    task_radius: Positive = DEFAULT_TASK_RADIUS_M
    battery_volume: Number | None = Field(None, description="charge in battery_capacity's "
                                                            "units; wins over battery_level")
    battery_level: Number = Field(100.0, description="percent, clamped to [0, 100]")
    gimbal: bool = Field(False, strict=True, description="a gimbal component (mavswarm)")
    heading: Number = Field(0.0, description="degrees, wrapped to [0, 360)")

    @model_validator(mode="after")
    def _altitudes(self) -> DroneEntity:
        for field, point in (("position", self.position), ("home_position", self.home_position)):
            z = point.z if point is not None and point.z is not None else 0.0
            if z < 0.0 or z > self.max_altitude:
                raise _field_error(f"{field}.z", "must be between 0 and max_altitude "
                                   f"({self.max_altitude:g}), got {z:g}")
        return self


class _Target(_Entity):
    id: Ident | None = Field(None, description="default t1, t2, ... by position in the list")
    name: Text
    radius: NonNegative = DEFAULT_TARGET_RADIUS_M

    @model_validator(mode="after")
    def _above_ground(self) -> _Target:
        position: PointEntity | None = getattr(self, "position", None)
        vertices: list[PointEntity] | None = getattr(self, "vertices", None)
        z = position.xyz()[2] if position is not None else vertices[0].xyz()[2] if vertices \
            else 0.0
        if z < 0.0:
            raise _field_error("position.z", f"must be >= 0, got {z:g}")
        return self


class FixedTarget(_Target):
    type: Literal["fixed"]
    position: PointEntity


class CircleTarget(_Target):
    """An area target: the disc of `radius` around `position`."""

    type: Literal["circle"]
    position: PointEntity


class WaypointTarget(_Target):
    """A charging station."""

    type: Literal["waypoint"]
    position: PointEntity
    charge_amount: Positive = Field(DEFAULT_CHARGE_AMOUNT_PCT,
                                    description="percent delivered per simulated minute")


class MovingTarget(_Target):
    """Moves with `velocity` (bouncing) or along `moving_path` for `moving_duration` s."""

    type: Literal["moving"]
    position: PointEntity
    velocity: PointEntity | None = Field(None, description="m/s")
    moving_path: list[PointEntity] = Field(default_factory=list)
    moving_duration: Number = Field(10.0, description="simulated seconds per run")


class PolygonTarget(_Target):
    """An area target bounded by its vertices."""

    type: Literal["polygon"]
    vertices: Polygon
    position: PointEntity | None = Field(None, description="default: the vertex mean, rounded")


TargetEntity = Annotated[FixedTarget | CircleTarget | WaypointTarget | MovingTarget
                         | PolygonTarget, Field(discriminator="type")]


class _Obstacle(_Entity):
    id: Ident | None = Field(None, description="default o1, o2, ... by position in the list")
    name: Text
    height: NonNegative = Field(DEFAULT_OBSTACLE_HEIGHT_M, description="m; 0: unbounded")


class PointObstacle(_Obstacle):
    type: Literal["point"]
    position: PointEntity
    radius: Positive = DEFAULT_POINT_OBSTACLE_RADIUS_M


class CircleObstacle(_Obstacle):
    type: Literal["circle"]
    position: PointEntity
    radius: Positive


class EllipseObstacle(_Obstacle):
    type: Literal["ellipse"]
    position: PointEntity
    width: Positive = Field(description="m, along x")
    length: Positive = Field(description="m, along y")


class PolygonObstacle(_Obstacle):
    type: Literal["polygon"]
    vertices: Polygon


ObstacleEntity = Annotated[PointObstacle | CircleObstacle | EllipseObstacle | PolygonObstacle,
                           Field(discriminator="type")]


def _wind_direction(raw: Any) -> float:
    if isinstance(raw, str) and raw.strip().lower() in WIND_DIRECTIONS_DEG:
        return WIND_DIRECTIONS_DEG[raw.strip().lower()]
    if isinstance(raw, int | float) and not isinstance(raw, bool):
        if not np.isfinite(raw):
            raise _problem("wind_direction", f"must be finite, got {show(raw)}")
        return float(raw)
    raise _problem("wind_direction", f"must be one of {', '.join(WIND_DIRECTIONS_DEG)} or "
                   f"degrees, got {show(raw)}")


WindDirection = Annotated[float, PlainValidator(_wind_direction), WithJsonSchema({
    "anyOf": [{"type": "string", "enum": list(WIND_DIRECTIONS_DEG)}, {"type": "number"}],
    "description": "where the wind comes from: a compass name (any case) or degrees"})]


class EnvironmentEntity(_Entity):
    """The weather, fixed for the whole session (other fields are kept but not used)."""

    id: str | None = None
    wind_speed: NonNegative = Field(0.0, description="m/s")
    wind_direction: WindDirection = 0.0


class OriginEntity(_Entity):
    """Where x = y = 0 is on Earth (mavswarm)."""

    latitude_deg: Number
    longitude_deg: Number
    altitude_amsl_m: Number = 0.0

    @model_validator(mode="after")
    def _on_earth(self) -> OriginEntity:
        self.geo()  # raises ValueError naming the field
        return self

    def geo(self) -> GeoOrigin:
        return GeoOrigin(self.latitude_deg, self.longitude_deg, self.altitude_amsl_m)


class ScenarioFile(_Entity):
    """A scenario: the MultiUAV-Plat session format's world and vehicles, with two optional
    mavswarm keys (origin, safety_margin_m)."""

    name: Text | None = Field(None, description="default: the file's name")
    task_type: Text = Field("others", description="area_search, area_assignment_and_patrol, "
                                                  "target_assignment, target_tracking or "
                                                  "others (anything else reads as others)")
    safety_margin_m: NonNegative = 2.0
    origin: OriginEntity | None = None
    environment: EnvironmentEntity | None = None
    drones: list[DroneEntity] = Field(min_length=1)
    targets: list[TargetEntity] = Field(default_factory=list)
    obstacles: list[ObstacleEntity] = Field(default_factory=list)


SCHEMA_PATH = Path(__file__).resolve().parent / "scenario.schema.json"


def json_schema() -> dict[str, Any]:
    """The JSON Schema of a scenario file (the MultiUAV-Plat session format's entities)."""
    schema = ScenarioFile.model_json_schema()
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["$id"] = "https://mavswarm.dev/schemas/scenario-1.json"
    return schema


def schema_text() -> str:
    """The JSON Schema file's text, as generated from the models."""
    return json.dumps(json_schema(), indent=2, sort_keys=True) + "\n"


if __name__ == "__main__":
    SCHEMA_PATH.write_text(schema_text(), encoding="utf-8")
    print(f"wrote {SCHEMA_PATH}")
