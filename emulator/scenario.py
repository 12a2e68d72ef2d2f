"""A mission scenario (world plus vehicles), read from a MultiUAV-Plat session file or built.

Session files follow the reference format (drones, targets, obstacles, environment) with two
optional mavswarm keys: ``origin`` ({latitude_deg, longitude_deg, altitude_amsl_m}) and
``safety_margin_m``. Defaults follow the reference's dict import. Weather is fixed: the
environment's wind is read once and never drifts. Every problem raises :class:`ScenarioError`
naming the file, the entity (list index and id) and the field.
"""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import NoReturn

import numpy as np
import shapely

from emulator.geo import DEFAULT_ORIGIN, GeoOrigin, wrap_heading_deg
from emulator.networks import MAX_FLEET_VEHICLES
from emulator.reference_mapping import (
    capacity_mah,
    home_altitude_m,
    moving_target_note,
    within_param,
)
from emulator.target_motion import EntryFn, MotionSpec, motion_spec, obstacle_entry
from emulator.world import CALM, OBSTACLE_KINDS, TARGET_KINDS, Obstacle, Target, Wind, World

__all__ = [
    "CHARGE_AMOUNT_PERIOD_S",
    "DEFAULT_CHARGE_AMOUNT_PCT",
    "DEFAULT_MODEL",
    "DEFAULT_OBSTACLE_HEIGHT_M",
    "DEFAULT_PERCEIVED_RADIUS_M",
    "DEFAULT_TARGET_RADIUS_M",
    "DEFAULT_TASK_RADIUS_M",
    "TASK_TYPES",
    "WIND_DIRECTIONS_DEG",
    "Scenario",
    "ScenarioError",
    "VehicleSpec",
    "default_scenario",
    "load_scenario",
    "scenario_from_dict",
]

# A charging station delivers its charge_amount (percent) per simulated minute.
CHARGE_AMOUNT_PERIOD_S = 60.0
DEFAULT_CHARGE_AMOUNT_PCT = 25.0
DEFAULT_PERCEIVED_RADIUS_M = 50.0
DEFAULT_TASK_RADIUS_M = 20.0
DEFAULT_TARGET_RADIUS_M = 1.0
DEFAULT_POINT_OBSTACLE_RADIUS_M = 1.0
DEFAULT_OBSTACLE_HEIGHT_M = 10.0
DEFAULT_MODEL = "generic-quad"
TASK_TYPES = ("area_search", "area_assignment_and_patrol", "target_assignment",
              "target_tracking", "others")
WIND_DIRECTIONS_DEG = {"north": 0.0, "northeast": 45.0, "east": 90.0, "southeast": 135.0,
                       "south": 180.0, "southwest": 225.0, "west": 270.0, "northwest": 315.0}

Point3 = tuple[float, float, float]
_REQUIRED = object()


class ScenarioError(ValueError):
    """Raised when a session file cannot be read: the message names the file, the entity
    (list index and id) and the field."""


@dataclass(frozen=True, slots=True)
class VehicleSpec:
    """Initial state and limits of one vehicle."""

    id: str
    name: str
    model: str
    position_m: Point3
    heading_deg: float
    home_m: Point3
    max_speed_m_s: float
    max_altitude_m: float
    perceived_radius_m: float
    task_radius_m: float
    battery_pct: float
    battery_capacity_mah: float
    gimbal: bool = False  # a gimbal component (MAVLink gimbal protocol v2) on the vehicle


@dataclass(frozen=True, slots=True)
class Scenario:
    """A world and the vehicles that start in it."""

    name: str
    task_type: str
    world: World
    vehicles: tuple[VehicleSpec, ...]
    source: str
    notes: tuple[str, ...] = ()
    """What was read differently from the file (emulator.reference_mapping)."""


def _show(value: object) -> str:
    """A field value as it reads in JSON, shortened."""
    try:
        text = json.dumps(value)
    except (TypeError, ValueError):
        text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


class _Entity:
    """Typed access to one JSON object's fields; every error names source, entity and field."""

    def __init__(self, source: str, label: str, data: object) -> None:
        self.source, self.label = source, label
        if not isinstance(data, Mapping):
            raise ScenarioError(f"{source}: {label}: must be a JSON object, got {_show(data)}")
        self.data: Mapping[str, object] = data
        ident = data.get("id")
        if isinstance(ident, str) and ident:
            self.label = f"{label} (id {ident})"

    def fail(self, field: str, problem: str) -> NoReturn:
        raise ScenarioError(f"{self.source}: {self.label}: {field} {problem}")

    def get(self, field: str, default: object = _REQUIRED) -> object:
        value = self.data.get(field)
        if value is None:
            if default is _REQUIRED:
                self.fail(field, "is required")
            return default
        return value

    def number(self, field: str, default: object = _REQUIRED, *, above: float | None = None,
               at_least: float | None = None) -> float:
        return self.as_number(field, self.get(field, default), above=above, at_least=at_least)

    def as_number(self, field: str, raw: object, *, above: float | None = None,
                  at_least: float | None = None) -> float:
        if isinstance(raw, bool) or not isinstance(raw, int | float):
            self.fail(field, f"must be a number, got {_show(raw)}")
        number = float(raw)
        if not math.isfinite(number):
            self.fail(field, f"must be finite, got {_show(raw)}")
        if above is not None and not number > above:
            self.fail(field, f"must be > {above:g}, got {_show(raw)}")
        if at_least is not None and not number >= at_least:
            self.fail(field, f"must be >= {at_least:g}, got {_show(raw)}")
        return number

    def text(self, field: str, default: object = _REQUIRED) -> str:
        raw = self.get(field, default)
        if not isinstance(raw, str) or not raw.strip():
            self.fail(field, f"must be a non-empty string, got {_show(raw)}")
        return raw

    def choice(self, field: str, options: tuple[str, ...]) -> str:
        raw = self.text(field)
        if raw not in options:
            self.fail(field, f"must be one of {', '.join(options)}; got {_show(raw)}")
        return raw

    def identifier(self, default: str) -> str:
        raw = self.get("id", default)
        if not isinstance(raw, str) or not raw:
            self.fail("id", f"must be a non-empty string, got {_show(raw)}")
        return raw

    def point(self, field: str, default: object = _REQUIRED) -> Point3:
        raw = self.get(field, default)
        return raw if isinstance(raw, tuple) else self.as_point(field, raw)

    def as_point(self, field: str, raw: object) -> Point3:
        if not isinstance(raw, Mapping) or raw.get("x") is None or raw.get("y") is None:
            self.fail(field, f"must be an object with numbers x and y, got {_show(raw)}")
        x, y = self.as_number(f"{field}.x", raw["x"]), self.as_number(f"{field}.y", raw["y"])
        z = raw.get("z")
        return x, y, 0.0 if z is None else self.as_number(f"{field}.z", z)

    def polygon(self, field: str) -> list[Point3]:
        """Vertices normalised as the reference does: a closing duplicate is dropped."""
        raw = self.get(field)
        if not isinstance(raw, list):
            self.fail(field, f"must be a list of {{x, y}} points, got {_show(raw)}")
        points = [self.as_point(f"{field}[{k}]", v) for k, v in enumerate(raw)]
        if len(points) >= 2 and points[-1][:2] == points[0][:2]:
            points.pop()
        if len(points) < 3:
            self.fail(field, f"must have at least 3 vertices, got {len(points)}")
        polygon = shapely.Polygon([p[:2] for p in points])
        if not polygon.is_valid:
            self.fail(field, f"must form a valid polygon ({shapely.is_valid_reason(polygon)})")
        if polygon.area <= 1e-9:
            self.fail(field, f"must enclose an area > 1e-9 m^2, got {polygon.area:g}")
        return points


def _rounded_mean(points: list[Point3]) -> Point3:
    xy = np.array([p[:2] for p in points])
    return float(round(xy[:, 0].mean())), float(round(xy[:, 1].mean())), points[0][2]


def _drone(e: _Entity, index: int, notes: list[str]) -> VehicleSpec:
    ident = e.identifier(f"d{index + 1}")
    name = e.text("name")
    model = e.text("model", DEFAULT_MODEL)
    max_speed = e.number("max_speed", above=0.0)
    max_altitude = e.number("max_altitude", above=0.0)
    capacity = e.number("battery_capacity", above=0.0)
    position = e.point("position", (0.0, 0.0, 0.0))
    home = e.point("home_position", position)
    for field, point in (("position", position), ("home_position", home)):
        if not 0.0 <= point[2] <= max_altitude:
            e.fail(f"{field}.z", f"must be between 0 and max_altitude ({max_altitude:g}), "
                   f"got {point[2]:g}")
    home_z, home_note = home_altitude_m(home[2], e.label)
    home = (home[0], home[1], home_z)
    capacity_flown, capacity_note = capacity_mah(capacity, e.label)
    notes.extend(n for n in (capacity_note, home_note) if n)
    limits = {}
    for field, param, raw in (
            ("max_speed", "MPC_XY_VEL_MAX", max_speed),
            ("max_altitude", "GF_MAX_VER_DIST", max_altitude),
            ("perceived_radius", "SIM_SENS_RAD",
             e.number("perceived_radius", DEFAULT_PERCEIVED_RADIUS_M, above=0.0)),
            ("task_radius", "SIM_TASK_RAD",
             e.number("task_radius", DEFAULT_TASK_RADIUS_M, above=0.0))):
        limits[field], note = within_param(raw, param, field, e.label)
        if note:
            notes.append(note)
    if e.data.get("battery_volume") is not None:
        volume = min(max(e.number("battery_volume"), 0.0), capacity)
        battery_pct = 100.0 * volume / capacity
    else:
        battery_pct = min(max(e.number("battery_level", 100.0), 0.0), 100.0)
    gimbal = e.get("gimbal", False)
    if not isinstance(gimbal, bool):
        e.fail("gimbal", f"must be true or false, got {_show(gimbal)}")
    return VehicleSpec(
        id=ident, name=name, model=model, position_m=position, gimbal=gimbal,
        heading_deg=wrap_heading_deg(e.number("heading", 0.0)), home_m=home,
        max_speed_m_s=limits["max_speed"], max_altitude_m=limits["max_altitude"],
        perceived_radius_m=limits["perceived_radius"], task_radius_m=limits["task_radius"],
        battery_pct=battery_pct, battery_capacity_mah=capacity_flown,
    )


def _target(e: _Entity, index: int, notes: list[str]) -> tuple[Target, Point3]:
    """The target and the point the reference tests for placement (the given position)."""
    ident, name = e.identifier(f"t{index + 1}"), e.text("name")
    kind = e.choice("type", TARGET_KINDS)
    radius = e.number("radius", DEFAULT_TARGET_RADIUS_M, at_least=0.0)
    if kind == "polygon":
        vertices = e.polygon("vertices")
        position = _rounded_mean(vertices)
        given = e.point("position", position)
        target = Target.polygon(ident, name, vertices, position_m=position, radius_m=radius)
    else:
        given = position = e.point("position")
        rate = None
        if kind == "waypoint":
            amount = e.number("charge_amount", DEFAULT_CHARGE_AMOUNT_PCT, above=0.0)
            rate = amount / CHARGE_AMOUNT_PERIOD_S
        motion = _motion(e, position) if kind == "moving" else None
        target = Target.disc(ident, name, kind, position, radius, charge_rate_pct_s=rate,
                             motion=motion)
    if given[2] < 0.0:
        e.fail("position.z", f"must be >= 0, got {given[2]:g}")
    return target, given


def _motion(e: _Entity, position: Point3) -> MotionSpec:
    """A moving target's velocity, path and duration (entities.md 3.3)."""
    velocity = e.point("velocity", None) if e.data.get("velocity") is not None else None
    raw_path = e.get("moving_path", [])
    if not isinstance(raw_path, list):
        e.fail("moving_path", f"must be a list of {{x, y}} points, got {_show(raw_path)}")
    path = [e.as_point(f"moving_path[{k}]", p) for k, p in enumerate(raw_path)]
    duration = e.number("moving_duration", 10.0)
    return motion_spec(position, velocity, path, duration)


def _meets_obstacle(motion: MotionSpec, entry: EntryFn) -> bool:
    """Whether a moving target's track (velocity: its first run; path: from its position
    along the path) runs into an obstacle, where our turning round differs from the
    reference's."""
    start = np.array(motion.start_m)
    if motion.mode == "velocity":
        points = [start, start + np.array(motion.velocity_m_s) * motion.duration_s]
    elif motion.mode == "path":
        points = [start, *(np.array(p) for p in motion.path_m)]
    else:
        return False
    return any(entry(a, b) is not None for a, b in itertools.pairwise(points))


def _obstacle(e: _Entity, index: int) -> Obstacle:
    ident, name = e.identifier(f"o{index + 1}"), e.text("name")
    kind = e.choice("type", OBSTACLE_KINDS)
    height = e.number("height", DEFAULT_OBSTACLE_HEIGHT_M, at_least=0.0)
    if kind == "polygon":
        vertices = e.polygon("vertices")
        center = _rounded_mean(vertices)[:2]
        return Obstacle.polygon(ident, name, vertices, height_m=height, center_m=center)
    center = e.point("position")[:2]
    if kind == "ellipse":
        width = e.number("width", above=0.0)
        length = e.number("length", above=0.0)
        return Obstacle.ellipse(ident, name, center, width, length, height_m=height)
    default_radius = DEFAULT_POINT_OBSTACLE_RADIUS_M if kind == "point" else _REQUIRED
    radius = e.number("radius", default_radius, above=0.0)
    return Obstacle.disc(ident, name, center, radius, height_m=height, kind=kind)


def _wind(source: str, data: object) -> Wind:
    if data is None:
        return CALM
    e = _Entity(source, "environment", data)
    speed = e.number("wind_speed", 0.0, at_least=0.0)
    direction = e.get("wind_direction", "north")
    if isinstance(direction, str) and direction.strip().lower() in WIND_DIRECTIONS_DEG:
        return Wind(speed, WIND_DIRECTIONS_DEG[direction.strip().lower()])
    if isinstance(direction, int | float) and not isinstance(direction, bool):
        return Wind(speed, e.number("wind_direction"))
    e.fail("wind_direction", f"must be one of {', '.join(WIND_DIRECTIONS_DEG)} or degrees, "
           f"got {_show(direction)}")


def _origin(source: str, data: object) -> GeoOrigin:
    if data is None:
        return DEFAULT_ORIGIN
    e = _Entity(source, "origin", data)
    lat, lon = e.number("latitude_deg"), e.number("longitude_deg")
    try:
        return GeoOrigin(lat, lon, e.number("altitude_amsl_m", 0.0))
    except ValueError as exc:
        raise ScenarioError(f"{source}: origin: {exc}") from None


def _entities(source: str, top: _Entity, key: str, required: bool) -> list[_Entity]:
    raw = top.get(key, _REQUIRED if required else [])
    if not isinstance(raw, list):
        top.fail(key, f"must be a list, got {_show(raw)}")
    if required and not raw:
        top.fail(key, "must list at least one entry")
    return [_Entity(source, f"{key}[{k}]", item) for k, item in enumerate(raw)]


def _check_unique(entities: list[_Entity], ids: list[str]) -> None:
    seen: dict[str, int] = {}
    for k, (e, ident) in enumerate(zip(entities, ids, strict=True)):
        if ident in seen:
            e.fail("id", f"{ident!r} is already used by entry [{seen[ident]}] of the same list")
        seen[ident] = k


def _check_placement(world: World, entities: list[_Entity], points: list[Point3],
                     field: str) -> None:
    if not points:
        return
    x, y, z = np.array(points, dtype=float).T
    for k in np.flatnonzero(world.inside_obstacles(x, y, z)):
        px, py, pz = points[k]
        hit = next(o for o in world.obstacles
                   if o.blocks_altitude(pz) and shapely.intersects_xy(o.footprint, px, py))
        entities[k].fail(field, f"({px:g}, {py:g}, {pz:g}) is inside obstacle {hit.name!r} "
                         f"(id {hit.id})")


def scenario_from_dict(data: Mapping[str, object], *, source: str = "<dict>") -> Scenario:
    """Build a scenario from a parsed session object; raises ScenarioError."""
    top = _Entity(source, "session", data)
    name = top.text("name", Path(source).stem or "session")
    task_type = top.text("task_type", "others")
    task_type = task_type if task_type in TASK_TYPES else "others"
    margin = top.number("safety_margin_m", 2.0, at_least=0.0)
    origin = _origin(source, top.data.get("origin"))
    wind = _wind(source, top.data.get("environment"))
    drone_entities = _entities(source, top, "drones", True)
    target_entities = _entities(source, top, "targets", False)
    obstacle_entities = _entities(source, top, "obstacles", False)
    obstacles = [_obstacle(e, k) for k, e in enumerate(obstacle_entities)]
    _check_unique(obstacle_entities, [o.id for o in obstacles])
    notes: list[str] = []
    placed = [_target(e, k, notes) for k, e in enumerate(target_entities)]
    targets = [t for t, _ in placed]
    entry = obstacle_entry(obstacles)
    notes.extend(moving_target_note(e.label, t.motion.mode)
                 for e, t in zip(target_entities, targets, strict=True)
                 if t.motion is not None and _meets_obstacle(t.motion, entry))
    _check_unique(target_entities, [t.id for t in targets])
    vehicles = [_drone(e, k, notes) for k, e in enumerate(drone_entities)]
    _check_unique(drone_entities, [v.id for v in vehicles])
    world = World(obstacles=obstacles, targets=targets, wind=wind, origin=origin,
                  safety_margin_m=margin)
    _check_placement(world, target_entities, [p for _, p in placed], "position")
    _check_placement(world, drone_entities, [v.position_m for v in vehicles], "position")
    _check_placement(world, drone_entities, [v.home_m for v in vehicles], "home_position")
    return Scenario(name, task_type, world, tuple(vehicles), source, tuple(notes))


def load_scenario(path: str | Path) -> Scenario:
    """Read a session JSON file; raises ScenarioError naming the file."""
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ScenarioError(f"{source}: cannot read the file: {exc}") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ScenarioError(f"{source}: not valid JSON: {exc}") from None
    if not isinstance(data, Mapping):
        raise ScenarioError(f"{source}: the top level must be a JSON object, got {_show(data)}")
    return scenario_from_dict(data, source=source)


def default_scenario(drone_count: int, *, origin: GeoOrigin = DEFAULT_ORIGIN) -> Scenario:
    """drone_count drones on the ground in rows of 10 at 5 m spacing from (0, 0), and a small
    demo world 60-400 m away: 3 fixed targets, a circle area, a charging station and one
    obstacle of each kind. Above 250 drones the fleet is several MAVLink networks
    (emulator.networks)."""
    if isinstance(drone_count, bool) or not isinstance(drone_count, int):
        raise ValueError(f"drone_count must be an integer, got {drone_count!r}")
    if not 1 <= drone_count <= MAX_FLEET_VEHICLES:
        raise ValueError(f"drone_count must be between 1 and {MAX_FLEET_VEHICLES}, "
                         f"got {drone_count}")
    vehicles = tuple(
        VehicleSpec(
            id=f"d{k + 1}", name=f"Drone {k + 1}", model=DEFAULT_MODEL,
            position_m=(5.0 * (k % 10), 5.0 * (k // 10), 0.0), heading_deg=0.0,
            home_m=(5.0 * (k % 10), 5.0 * (k // 10), 0.0), max_speed_m_s=12.0,
            max_altitude_m=120.0, perceived_radius_m=DEFAULT_PERCEIVED_RADIUS_M,
            task_radius_m=DEFAULT_TASK_RADIUS_M, battery_pct=100.0, battery_capacity_mah=5000.0,
        )
        for k in range(drone_count)
    )
    targets = (
        Target.disc("t1", "Fixed Target 1", "fixed", (150.0, 50.0, 0.0), 5.0),
        Target.disc("t2", "Fixed Target 2", "fixed", (-100.0, 200.0, 0.0), 5.0),
        Target.disc("t3", "Fixed Target 3", "fixed", (250.0, 300.0, 0.0), 5.0),
        Target.disc("t4", "Search Area 1", "circle", (300.0, 100.0, 0.0), 40.0),
        Target.disc("t5", "Charging Station 1", "waypoint", (120.0, -60.0, 0.0), 8.0,
                    charge_rate_pct_s=DEFAULT_CHARGE_AMOUNT_PCT / CHARGE_AMOUNT_PERIOD_S),
    )
    obstacles = (
        Obstacle.disc("o1", "Point Obstacle 1", (120.0, 60.0), 3.0, kind="point"),
        Obstacle.disc("o2", "Circle Obstacle 2", (200.0, 180.0), 15.0, height_m=15.0),
        Obstacle.ellipse("o3", "Ellipse Obstacle 3", (-90.0, 40.0), 20.0, 10.0),
        Obstacle.polygon("o4", "Polygon Obstacle 4",
                         [(180.0, -80.0), (210.0, -80.0), (210.0, -50.0), (180.0, -50.0)]),
    )
    world = World(obstacles=obstacles, targets=targets, wind=CALM, origin=origin)
    return Scenario(f"Default scenario ({drone_count} drones)", "others", world, vehicles,
                    "defaults")
