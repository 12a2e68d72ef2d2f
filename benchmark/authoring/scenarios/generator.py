"""Seeded generation of the world of each benchmark session (drones, targets, obstacles, weather).

Every random choice of a session comes from one ``random.Random(session_seed(family, level,
index))``, so the same key always gives the same, byte-identical session. Draw order: the
environment, the base corner, the drones, the family's targets (area targets before the
obstacles, fixed targets after them), the obstacles, then the charging stations. Sessions are
returned without tasks.
"""

from __future__ import annotations

import hashlib
import math
import random
from collections.abc import Callable
from typing import Any

from benchmark.authoring.scenarios.families import (
    FAMILIES,
    RESILIENCE_FIXED_TARGETS,
    TRACKING_TARGETS,
    FamilySpec,
    family_spec,
    moving_count,
)
from benchmark.authoring.scenarios.levels import LEVELS, LevelSpec, level_spec, sized_spec
from benchmark.authoring.scenarios.placement import (
    MAP_MARGIN_M,
    Footprint,
    Layout,
    ShapeTemplate,
    convex_offsets,
    rectangle_offsets,
)
from emulator.geo import DEFAULT_ORIGIN

__all__ = [
    "BASE_CORNERS",
    "DRONE_MODELS",
    "SCHEMA",
    "SESSION_INDICES",
    "WEATHERS",
    "WIND_DIRECTIONS",
    "all_session_keys",
    "generate_world",
    "session_id",
    "session_seed",
]

SCHEMA = "mavswarm.session/1"
SESSION_INDICES: tuple[int, ...] = (1, 2, 3, 4, 5)
DRONE_MODELS: tuple[str, ...] = ("MS-Quad-A", "MS-Quad-B", "MS-Hexa-C", "MS-Octo-D")
WEATHERS: tuple[str, ...] = ("clear", "partly_cloudy", "cloudy", "windy")
WIND_DIRECTIONS: tuple[str, ...] = ("north", "northeast", "east", "southeast", "south",
                                    "southwest", "west", "northwest")
# The drones' base: a disc whose centre lies this far in from both edges of one map corner.
BASE_CORNERS: tuple[str, ...] = ("southwest", "southeast", "northwest", "northeast")
BASE_INSET_M = 60.0
SAFETY_MARGIN_M = 2.0

MAX_SPEED_M_S = (12, 20)
MAX_ALTITUDE_M = 120
PERCEIVED_RADIUS_M, TASK_RADIUS_M = 50, 20
VARIED_PERCEIVED_RADIUS_M, VARIED_TASK_RADIUS_M = (40, 60), (15, 25)
BATTERY_CAPACITY_MAH = (4000.0, 6000.0)
FIXED_TARGET_RADIUS_M = (3.0, 10.0)
STATION_RADIUS_M = (8.0, 12.0)
CHARGE_AMOUNT_PCT_PER_MIN = (20.0, 50.0)
CIRCLE_AREA_PROBABILITY = 0.4
AREA_POLYGON_SHAPES: tuple[str, ...] = ("square", "rectangle", "convex")
OBSTACLE_SHAPE_WEIGHTS = {"circle": 3, "square": 2, "ellipse": 2, "point": 1, "rectangle": 2,
                          "convex": 2}
POINT_OBSTACLE_RADIUS_M = (2.0, 5.0)
MOVING_TARGET_RADIUS_M = (3.0, 8.0)
MOVING_SPEED_M_S = (1.0, 3.0)
MOVING_DURATION_S = (8.0, 20.0)
PATH_MODE_EVERY = 3  # every third moving target follows a path, the others a velocity
WALL_PROBABILITY = 0.7  # share of obstacles with height 0 (blocking every altitude)
BUILDING_HEIGHT_M = (15.0, 60.0)
# Obstacle names by (shape, blocks every altitude).
_OBSTACLE_NAMES = {
    ("point", True): "Mast", ("point", False): "Pole",
    ("circle", True): "Tower", ("circle", False): "Silo",
    ("ellipse", True): "Ridge", ("ellipse", False): "Hangar",
    ("square", True): "Cliff Block", ("square", False): "Building",
    ("rectangle", True): "Wall", ("rectangle", False): "Warehouse",
    ("convex", True): "Rock Outcrop", ("convex", False): "Complex",
}

Session = dict[str, Any]
TemplateFor = Callable[[float], ShapeTemplate]


def _check_key(family: str, level: str, index: int, max_index: int = SESSION_INDICES[-1]
               ) -> tuple[FamilySpec, LevelSpec]:
    fam, spec = family_spec(family), level_spec(level)
    if (isinstance(index, bool) or not isinstance(index, int)
            or not SESSION_INDICES[0] <= index <= max_index):
        raise ValueError(f"index must be an integer from {SESSION_INDICES[0]} to "
                         f"{max_index}; got {index!r}")
    return fam, spec


def session_id(family: str, level: str, index: int, *,
               max_index: int = SESSION_INDICES[-1]) -> str:
    """The session's id, e.g. 'area_search-easy-1'; raises ValueError on a bad key (an index
    above max_index: the shipped suite has 5 sessions per cell, a drawn one may have more)."""
    _check_key(family, level, index, max_index)
    return f"{family}-{level}-{index}"


def session_seed(family: str, level: str, index: int, *, secret: str = "",
                 max_index: int = SESSION_INDICES[-1]) -> int:
    """A stable 53-bit seed: the first 8 bytes of sha256("mavswarm/<family>/<level>/<index>")
    shifted right by 11 bits (so it survives a JSON round trip through doubles). With a
    secret, sha256("mavswarm/<secret>/<family>/<level>/<index>"): a private split nobody
    draws again without the secret."""
    _check_key(family, level, index, max_index)
    label = f"{secret}/" if secret else ""
    digest = hashlib.sha256(f"mavswarm/{label}{family}/{level}/{index}".encode()).digest()
    return int.from_bytes(digest[:8], "big") >> 11


def all_session_keys() -> tuple[tuple[str, str, int], ...]:
    """The 125 (family, level, index) keys: family-major, then level, then index."""
    return tuple((f, lv, i) for f in FAMILIES for lv in LEVELS for i in SESSION_INDICES)


def _size(rng: random.Random, bounds: tuple[float, float], shrink: float) -> float:
    low, high = bounds
    return low + rng.random() * (high - low) * shrink


def _convex(rng: random.Random, size_m: float) -> ShapeTemplate:
    count = rng.randint(4, 8)
    start, step = rng.uniform(0.0, 2.0 * math.pi), 2.0 * math.pi / count
    angles = [start + (k + rng.uniform(-0.35, 0.35)) * step for k in range(count)]
    offsets = convex_offsets(size_m, size_m * rng.uniform(0.55, 1.0), angles,
                             rng.uniform(0.0, 180.0))
    return ShapeTemplate.polygon(offsets)


def _rectangle(rng: random.Random, size_m: float, width_share: tuple[float, float]
               ) -> ShapeTemplate:
    half_width = size_m * rng.uniform(*width_share)
    return ShapeTemplate.polygon(rectangle_offsets(size_m, half_width, rng.uniform(0.0, 180.0)))


def _shape(rng: random.Random, shape: str, size_m: float) -> ShapeTemplate:
    """A random footprint of the named shape whose half-extent is size_m."""
    if shape == "circle":
        return ShapeTemplate.disc(size_m)
    if shape == "square":
        return ShapeTemplate.polygon(rectangle_offsets(size_m, size_m, 0.0))
    if shape == "rectangle":
        return _rectangle(rng, size_m, (0.3, 0.8))
    if shape == "ellipse":
        minor = size_m * rng.uniform(0.4, 0.9)
        return ShapeTemplate.ellipse(*((size_m, minor) if rng.random() < 0.5 else (minor, size_m)))
    if shape == "convex":
        return _convex(rng, size_m)
    raise ValueError(f"unknown shape {shape!r}")


def _xyz(point: tuple[float, float]) -> dict[str, float]:
    return {"x": point[0], "y": point[1], "z": 0.0}


def _vertices(footprint: Footprint) -> list[dict[str, float]]:
    return [{"x": x, "y": y} for x, y in footprint.vertices_m]


def _environment(rng: random.Random) -> dict[str, Any]:
    weather = rng.choice(WEATHERS)
    wind = rng.uniform(4.0, 6.0) if weather == "windy" else rng.uniform(0.0, 4.0)
    return {"weather": weather, "temperature": round(rng.uniform(6.0, 28.0), 1),
            "humidity": round(rng.uniform(30.0, 80.0), 1), "wind_speed": round(wind, 1),
            "wind_direction": rng.choice(WIND_DIRECTIONS)}


def _base(rng: random.Random, spec: LevelSpec) -> tuple[str, tuple[float, float]]:
    corner = rng.choice(BASE_CORNERS)
    x = BASE_INSET_M if corner.endswith("west") else spec.map_width_m - BASE_INSET_M
    y = BASE_INSET_M if corner.startswith("south") else spec.map_height_m - BASE_INSET_M
    return corner, (x, y)


def _drones(rng: random.Random, spec: LevelSpec, layout: Layout,
            base: tuple[float, float]) -> list[dict[str, Any]]:
    drones = []
    for k in range(1, spec.drone_count + 1):
        spot = layout.place(rng, "drone", lambda _s: ShapeTemplate.point(),
                            label=f"drone d{k}", within=(base, spec.base_radius_m))
        if spec.varied_sensor_radii:
            perceived = rng.randint(*VARIED_PERCEIVED_RADIUS_M)
            task = rng.randint(*VARIED_TASK_RADIUS_M)
        else:
            perceived, task = PERCEIVED_RADIUS_M, TASK_RADIUS_M
        drones.append({
            "id": f"d{k}", "name": f"Drone {k}", "model": rng.choice(DRONE_MODELS),
            "position": _xyz(spot.center_m), "heading": 0.0, "home_position": _xyz(spot.center_m),
            "max_speed": rng.randint(*MAX_SPEED_M_S), "max_altitude": MAX_ALTITUDE_M,
            "perceived_radius": perceived, "task_radius": task, "battery_level": 100.0,
            "battery_capacity": round(rng.uniform(*BATTERY_CAPACITY_MAH), 1),
        })
    return drones


def _area_target(rng: random.Random, spec: LevelSpec, layout: Layout, name: str
                 ) -> dict[str, Any]:
    circle = rng.random() < CIRCLE_AREA_PROBABILITY
    shape = "circle" if circle else rng.choice(AREA_POLYGON_SHAPES)

    def template_for(shrink: float) -> ShapeTemplate:
        size = _size(rng, spec.area_size_m, shrink)
        if shape == "rectangle":
            return _rectangle(rng, size, (0.45, 0.9))
        return _shape(rng, shape, size)

    spot = layout.place(rng, "target", template_for, label=name)
    if spot.shape == "disc":
        return {"name": name, "type": "circle", "position": _xyz(spot.center_m),
                "radius": spot.radius_m}
    return {"name": name, "type": "polygon", "vertices": _vertices(spot)}


def _disc_target(rng: random.Random, layout: Layout, name: str, kind: str) -> dict[str, Any]:
    bounds = STATION_RADIUS_M if kind == "waypoint" else FIXED_TARGET_RADIUS_M
    spot = layout.place(rng, "target", lambda s: ShapeTemplate.disc(_size(rng, bounds, s)),
                        label=name)
    target = {"name": name, "type": kind, "position": _xyz(spot.center_m),
              "radius": spot.radius_m}
    if kind == "waypoint":
        target["charge_amount"] = round(rng.uniform(*CHARGE_AMOUNT_PCT_PER_MIN), 1)
    return target


def _moving_target(rng: random.Random, layout: Layout, name: str, path_mode: bool
                   ) -> dict[str, Any]:
    """A moving target whose whole track (a segment, or a three-point path) and disc lie in a
    placed disc, so obstacles keep their clearance from everywhere it goes."""
    radius = round(rng.uniform(*MOVING_TARGET_RADIUS_M), 1)
    speed = rng.uniform(*MOVING_SPEED_M_S)
    duration = round(rng.uniform(*MOVING_DURATION_S), 1)
    half = speed * duration / 2.0
    spot = layout.place(rng, "target", lambda _s: ShapeTemplate.disc(half + radius + 1.0),
                        label=name)
    (cx, cy), angle = spot.center_m, rng.uniform(0.0, 2.0 * math.pi)
    ux, uy = math.cos(angle), math.sin(angle)
    start = (round(cx - half * ux, 1), round(cy - half * uy, 1))
    target: dict[str, Any] = {"name": name, "type": "moving", "position": _xyz(start),
                              "radius": radius}
    if path_mode:
        bend = rng.uniform(-0.5, 0.5) * half
        middle = (round(cx - bend * uy, 1), round(cy + bend * ux, 1))
        end = (round(cx + half * ux, 1), round(cy + half * uy, 1))
        points = [start, middle, end]
        length = math.dist(start, middle) + math.dist(middle, end)
        target["moving_path"] = [_xyz(p) for p in points]
        target["moving_duration"] = round(length / speed, 1)
    else:
        target["velocity"] = {"x": round(speed * ux, 2), "y": round(speed * uy, 2), "z": 0.0}
        target["moving_duration"] = duration
    return target


def _obstacles(rng: random.Random, spec: LevelSpec, layout: Layout) -> list[dict[str, Any]]:
    weights = [OBSTACLE_SHAPE_WEIGHTS[s] for s in spec.obstacle_shapes]
    counters: dict[str, int] = {}
    obstacles = []
    for k in range(1, spec.obstacle_count + 1):
        shape = rng.choices(spec.obstacle_shapes, weights)[0]
        wall = rng.random() < WALL_PROBABILITY
        height = 0.0 if wall else round(rng.uniform(*BUILDING_HEIGHT_M), 1)
        prefix = _OBSTACLE_NAMES[shape, wall]
        counters[prefix] = counters.get(prefix, 0) + 1
        name = f"{prefix} {counters[prefix]}"

        def template_for(shrink: float, shape: str = shape) -> ShapeTemplate:
            if shape == "point":
                return ShapeTemplate.disc(_size(rng, POINT_OBSTACLE_RADIUS_M, shrink))
            return _shape(rng, shape, _size(rng, spec.obstacle_size_m, shrink))

        spot = layout.place(rng, "obstacle", template_for, label=f"obstacle o{k} ({name})")
        entry: dict[str, Any] = {"id": f"o{k}", "name": name, "type": shape,
                                 "position": _xyz(spot.center_m)}
        if spot.shape == "disc":
            entry["radius"] = spot.radius_m
        elif spot.shape == "ellipse":
            entry["width"], entry["length"] = spot.semi_axes_m
        else:
            entry["type"], entry["vertices"] = "polygon", _vertices(spot)
        entry["height"] = height
        obstacles.append(entry)
    return obstacles


def _with_stations(rng: random.Random, layout: Layout, targets: list[dict[str, Any]],
                   stations: int) -> list[dict[str, Any]]:
    """`targets` followed by `stations` charging stations drawn after them, numbered t1, t2..."""
    targets = targets + [_disc_target(rng, layout, f"Charging Station {k}", "waypoint")
                         for k in range(1, stations + 1)]
    return [{"id": f"t{k}", **t} for k, t in enumerate(targets, start=1)]


def _stations_text(stations: int) -> str:
    return "charging station" if stations == 1 else "charging stations"


def _description(fam: FamilySpec, spec: LevelSpec, corner: str, main: int, stations: int
                 ) -> str:
    things = "area targets" if fam.area_targets else "fixed targets"
    station_text = _stations_text(stations)
    return (f"A {spec.map_width_m} x {spec.map_height_m} m map with {spec.drone_count} drones "
            f"at a base in the {corner} corner, {main} {things}, {stations} {station_text} "
            f"and {spec.obstacle_count} obstacles.")


def generate_world(family: str, level: str, index: int, *, secret: str = "",
                   max_index: int = SESSION_INDICES[-1], drones: int = 0,
                   map_size_m: float = 0.0) -> Session:
    """The session dict (without tasks) of one benchmark key (drawn from the secret's seeds
    when one is given), with the level's drone count and map size unless `drones` or
    `map_size_m` (a square map's side) say otherwise; raises ValueError on a bad key or size
    and PlacementError if the counts cannot be placed."""
    fam, spec = _check_key(family, level, index, max_index)
    spec = sized_spec(spec, drones, map_size_m)
    seed = session_seed(family, level, index, secret=secret, max_index=max_index)
    rng = random.Random(seed)
    layout = Layout(spec.map_width_m, spec.map_height_m, margin_m=MAP_MARGIN_M)
    environment = _environment(rng)
    corner, base = _base(rng, spec)
    placed = _drones(rng, spec, layout, base)
    stations = spec.charging_station_count
    if fam.family == "target_tracking":
        return _tracking_world(family, spec, index, seed, rng, layout, placed, environment,
                               corner)
    if fam.family == "resilience":
        return _resilience_world(family, spec, index, seed, rng, layout, placed,
                                 environment, corner)
    main = spec.target_count(fam.area_targets) - stations
    names = [f"{fam.target_name} {k}" for k in range(1, main + 1)]
    targets = [_area_target(rng, spec, layout, n) for n in names] if fam.area_targets else []
    obstacles = _obstacles(rng, spec, layout)
    if not fam.area_targets:
        targets = [_disc_target(rng, layout, n, "fixed") for n in names]
    targets = _with_stations(rng, layout, targets, stations)
    return _session(fam, spec, index, seed, _description(fam, spec, corner, main, stations),
                    environment, placed, targets, obstacles)


def _tracking_world(family: str, spec: LevelSpec, index: int, seed: int, rng: random.Random,
                    layout: Layout, drones: list[dict[str, Any]], environment: dict[str, Any],
                    corner: str) -> Session:
    """target_tracking: moving targets' tracks placed before the obstacles, fixed targets and
    charging stations after them."""
    fam, level = family_spec(family), spec.level
    movers = moving_count(family, level)
    fixed = TRACKING_TARGETS[level] - movers
    targets = [_moving_target(rng, layout, f"Moving Target {k}", k % PATH_MODE_EVERY == 0)
               for k in range(1, movers + 1)]
    obstacles = _obstacles(rng, spec, layout)
    targets += [_disc_target(rng, layout, f"Fixed Target {k}", "fixed")
                for k in range(1, fixed + 1)]
    stations = spec.charging_station_count
    targets = _with_stations(rng, layout, targets, stations)
    station_text = _stations_text(stations)
    description = (f"A {spec.map_width_m} x {spec.map_height_m} m map with {spec.drone_count} "
                   f"drones at a base in the {corner} corner, {movers} moving targets, {fixed} "
                   f"fixed target{'' if fixed == 1 else 's'}, {stations} {station_text} and "
                   f"{spec.obstacle_count} obstacles.")
    return _session(fam, spec, index, seed, description, environment, drones, targets,
                    obstacles)


def _resilience_world(family: str, spec: LevelSpec, index: int, seed: int,
                      rng: random.Random, layout: Layout, drones: list[dict[str, Any]],
                      environment: dict[str, Any], corner: str) -> Session:
    """resilience: the area families' area targets placed before the obstacles, then
    RESILIENCE_FIXED_TARGETS fixed targets and the charging stations."""
    fam, level = family_spec(family), spec.level
    stations = spec.charging_station_count
    areas = spec.area_target_count - stations
    targets = [_area_target(rng, spec, layout, f"Search Area {k}") for k in range(1, areas + 1)]
    obstacles = _obstacles(rng, spec, layout)
    fixed = RESILIENCE_FIXED_TARGETS[level]
    targets += [_disc_target(rng, layout, f"Target {k}", "fixed") for k in range(1, fixed + 1)]
    targets = _with_stations(rng, layout, targets, stations)
    station_text = _stations_text(stations)
    description = (f"A {spec.map_width_m} x {spec.map_height_m} m map with {spec.drone_count} "
                   f"drones at a base in the {corner} corner, {areas} area targets, {fixed} "
                   f"fixed targets, {stations} {station_text} and {spec.obstacle_count} "
                   f"obstacles.")
    return _session(fam, spec, index, seed, description, environment, drones, targets,
                    obstacles)


def _session(fam: FamilySpec, spec: LevelSpec, index: int, seed: int, description: str,
             environment: dict[str, Any], drones: list[dict[str, Any]],
             targets: list[dict[str, Any]], obstacles: list[dict[str, Any]]) -> Session:
    family, level = fam.family, spec.level
    return {
        "schema": SCHEMA, "id": f"{family}-{level}-{index}", "family": family,
        "level": level, "index": index, "seed": seed,
        "name": f"{fam.title}, {level}, #{index}",
        "description": description,
        "task_type": fam.task_type, "map_size_m": [spec.map_width_m, spec.map_height_m],
        "safety_margin_m": SAFETY_MARGIN_M,
        "origin": {"latitude_deg": DEFAULT_ORIGIN.latitude_deg,
                   "longitude_deg": DEFAULT_ORIGIN.longitude_deg,
                   "altitude_amsl_m": DEFAULT_ORIGIN.altitude_amsl_m},
        "environment": environment, "drones": drones, "targets": targets,
        "obstacles": obstacles, "tasks": [],
    }
