"""A mission scenario (world plus vehicles), read from a MultiUAV-Plat session file or built.

Session files follow the reference format (drones, targets, obstacles, environment) with two
optional mavswarm keys: ``origin`` ({latitude_deg, longitude_deg, altitude_amsl_m}) and
``safety_margin_m``. Defaults follow the reference's dict import. Weather is fixed: the
environment's wind is read once and never drifts. The file's shape and field rules are the
pydantic models of `emulator.scenario_model` (its JSON Schema: `scenario.schema.json` beside
them); this module builds the world from a validated file. Every problem raises
:class:`ScenarioError` naming the file, the entity (list index and id) and the field.
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import NoReturn

import numpy as np
import shapely
from pydantic import ValidationError

from emulator.geo import DEFAULT_ORIGIN, GeoOrigin, wrap_heading_deg
from emulator.networks import MAX_FLEET_VEHICLES
from emulator.reference_mapping import (
    capacity_mah,
    home_altitude_m,
    moving_target_note,
    within_param,
)
from emulator.scenario_errors import describe_error, entity_label, show
from emulator.scenario_model import (
    DEFAULT_CHARGE_AMOUNT_PCT,
    DEFAULT_MODEL,
    DEFAULT_OBSTACLE_HEIGHT_M,
    DEFAULT_PERCEIVED_RADIUS_M,
    DEFAULT_TARGET_RADIUS_M,
    DEFAULT_TASK_RADIUS_M,
    WIND_DIRECTIONS_DEG,
    DroneEntity,
    EllipseObstacle,
    MovingTarget,
    ObstacleEntity,
    PolygonObstacle,
    PolygonTarget,
    ScenarioFile,
    TargetEntity,
    WaypointTarget,
    rounded_mean,
)
from emulator.target_motion import EntryFn, MotionSpec, motion_spec, obstacle_entry
from emulator.world import CALM, Obstacle, Target, Wind, World

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
    "scenario_from_model",
    "validate_scenario",
]

# A charging station delivers its charge_amount (percent) per simulated minute.
CHARGE_AMOUNT_PERIOD_S = 60.0
TASK_TYPES = ("area_search", "area_assignment_and_patrol", "target_assignment",
              "target_tracking", "others")

Point3 = tuple[float, float, float]


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


def _drone(d: DroneEntity, index: int, label: str, notes: list[str]) -> VehicleSpec:
    position = d.position.xyz()
    home = position if d.home_position is None else d.home_position.xyz()
    home_z, home_note = home_altitude_m(home[2], label)
    capacity_flown, capacity_note = capacity_mah(d.battery_capacity, label)
    notes.extend(n for n in (capacity_note, home_note) if n)
    limits = {}
    for field, param, raw in (("max_speed", "MPC_XY_VEL_MAX", d.max_speed),
                              ("max_altitude", "GF_MAX_VER_DIST", d.max_altitude),
                              ("perceived_radius", "SIM_SENS_RAD", d.perceived_radius),
                              ("task_radius", "SIM_TASK_RAD", d.task_radius)):
        limits[field], note = within_param(raw, param, field, label)
        if note:
            notes.append(note)
    if d.battery_volume is not None:
        volume = min(max(d.battery_volume, 0.0), d.battery_capacity)
        battery_pct = 100.0 * volume / d.battery_capacity
    else:
        battery_pct = min(max(d.battery_level, 0.0), 100.0)
    return VehicleSpec(
        id=d.id or f"d{index + 1}", name=d.name, model=d.model, position_m=position,
        gimbal=d.gimbal, heading_deg=wrap_heading_deg(d.heading),
        home_m=(home[0], home[1], home_z),
        max_speed_m_s=limits["max_speed"], max_altitude_m=limits["max_altitude"],
        perceived_radius_m=limits["perceived_radius"], task_radius_m=limits["task_radius"],
        battery_pct=battery_pct, battery_capacity_mah=capacity_flown,
    )


def _target(t: TargetEntity, index: int) -> tuple[Target, Point3]:
    """The target and the point the reference tests for placement (the given position)."""
    ident = t.id or f"t{index + 1}"
    if isinstance(t, PolygonTarget):
        vertices = [v.xyz() for v in t.vertices]
        position = rounded_mean(t.vertices)
        given = position if t.position is None else t.position.xyz()
        return Target.polygon(ident, t.name, vertices, position_m=position,
                              radius_m=t.radius), given
    position = t.position.xyz()
    rate = t.charge_amount / CHARGE_AMOUNT_PERIOD_S if isinstance(t, WaypointTarget) else None
    motion = None
    if isinstance(t, MovingTarget):
        velocity = None if t.velocity is None else t.velocity.xyz()
        motion = motion_spec(position, velocity, [p.xyz() for p in t.moving_path],
                             t.moving_duration)
    return Target.disc(ident, t.name, t.type, position, t.radius, charge_rate_pct_s=rate,
                       motion=motion), position


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


def _obstacle(o: ObstacleEntity, index: int) -> Obstacle:
    ident = o.id or f"o{index + 1}"
    if isinstance(o, PolygonObstacle):
        vertices = [v.xyz() for v in o.vertices]
        center = rounded_mean(o.vertices)[:2]
        return Obstacle.polygon(ident, o.name, vertices, height_m=o.height, center_m=center)
    center = (o.position.x, o.position.y)
    if isinstance(o, EllipseObstacle):
        return Obstacle.ellipse(ident, o.name, center, o.width, o.length, height_m=o.height)
    return Obstacle.disc(ident, o.name, center, o.radius, height_m=o.height, kind=o.type)


class _Labels:
    """Where an entity is in the file, for messages: `source: drones[3] (id d4): ...`."""

    def __init__(self, source: str, data: Mapping[str, object]) -> None:
        self.source, self.data = source, data

    def __call__(self, key: str, index: int) -> str:
        return entity_label(self.data, key, index)

    def fail(self, key: str, index: int, field: str, problem: str) -> NoReturn:
        raise ScenarioError(f"{self.source}: {self(key, index)}: {field} {problem}")


def _check_unique(labels: _Labels, key: str, ids: list[str]) -> None:
    seen: dict[str, int] = {}
    for k, ident in enumerate(ids):
        if ident in seen:
            labels.fail(key, k, "id", f"{ident!r} is already used by entry [{seen[ident]}] of "
                        "the same list")
        seen[ident] = k


def _check_placement(world: World, labels: _Labels, key: str, points: list[Point3],
                     field: str) -> None:
    if not points:
        return
    x, y, z = np.array(points, dtype=float).T
    for k in np.flatnonzero(world.inside_obstacles(x, y, z)):
        px, py, pz = points[k]
        hit = next(o for o in world.obstacles
                   if o.blocks_altitude(pz) and shapely.intersects_xy(o.footprint, px, py))
        labels.fail(key, int(k), field, f"({px:g}, {py:g}, {pz:g}) is inside obstacle "
                    f"{hit.name!r} (id {hit.id})")


def validate_scenario(data: object, *, source: str = "<dict>") -> ScenarioFile:
    """The validated model of a parsed session object; raises ScenarioError naming the file,
    the entity and the field (the first problem found)."""
    try:
        return ScenarioFile.model_validate(data)
    except ValidationError as error:
        first = error.errors(include_url=False)[0]
        raise ScenarioError(f"{source}: {describe_error(first, data)}") from None


def scenario_from_dict(data: Mapping[str, object], *, source: str = "<dict>") -> Scenario:
    """Build a scenario from a parsed session object; raises ScenarioError."""
    return scenario_from_model(validate_scenario(data, source=source), data, source=source)


def scenario_from_model(model: ScenarioFile, data: Mapping[str, object], *,
                        source: str = "<dict>") -> Scenario:
    """Build a scenario from a validated file (`data`: the object it was read from, for
    messages); raises ScenarioError for duplicate ids and entities inside obstacles."""
    labels = _Labels(source, data)
    name = model.name or Path(source).stem or "session"
    task_type = model.task_type if model.task_type in TASK_TYPES else "others"
    origin = DEFAULT_ORIGIN if model.origin is None else model.origin.geo()
    environment = model.environment
    wind = CALM if environment is None else Wind(environment.wind_speed,
                                                 environment.wind_direction)
    obstacles = [_obstacle(o, k) for k, o in enumerate(model.obstacles)]
    _check_unique(labels, "obstacles", [o.id for o in obstacles])
    notes: list[str] = []
    placed = [_target(t, k) for k, t in enumerate(model.targets)]
    targets = [t for t, _ in placed]
    entry = obstacle_entry(obstacles)
    notes.extend(moving_target_note(labels("targets", k), t.motion.mode)
                 for k, t in enumerate(targets)
                 if t.motion is not None and _meets_obstacle(t.motion, entry))
    _check_unique(labels, "targets", [t.id for t in targets])
    vehicles = [_drone(d, k, labels("drones", k), notes) for k, d in enumerate(model.drones)]
    _check_unique(labels, "drones", [v.id for v in vehicles])
    world = World(obstacles=obstacles, targets=targets, wind=wind, origin=origin,
                  safety_margin_m=model.safety_margin_m)
    _check_placement(world, labels, "targets", [p for _, p in placed], "position")
    _check_placement(world, labels, "drones", [v.position_m for v in vehicles], "position")
    _check_placement(world, labels, "drones", [v.home_m for v in vehicles], "home_position")
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
        raise ScenarioError(f"{source}: the top level must be a JSON object, got {show(data)}")
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
