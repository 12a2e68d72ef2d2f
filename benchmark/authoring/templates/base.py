"""What a task template is and what it produces.

A template turns a session's static world and a seeded random generator into a `TaskDraft`:
the instruction in several phrasings (the first is the one given to agents, the others are
aliases), a hidden check tree, and a hidden oracle plan. Templates only read the session's
static data (entities, map), never where earlier tasks left the drones, so a session file
depends on its seed alone.

Oracle plans are lists of phases; a phase is a list of operations, each for one drone or a
team. Within a phase, operations of different drones run concurrently and those of one drone
run in order. Operations (all lengths in metres, angles in degrees; each is a type of
`benchmark.authoring.plan_steps`, which reads and checks them):

- ``{"op": "takeoff", "drone", "altitude_m"}``
- ``{"op": "goto", "drone", "x", "y", "z"}``: obstacle-free path, taking off first if needed
- ``{"op": "path", "drone", "points": [[x, y, z], ...]}``: visit each point in order
- ``{"op": "land", "drone"}``, ``{"op": "hover", "drone", "duration_s"}``
- ``{"op": "rotate", "drone", "heading_deg"}``, ``{"op": "altitude", "drone", "altitude_m"}``
- ``{"op": "towards", "drone", "heading_deg", "distance_m"}``: a straight move
- ``{"op": "photo", "drone"}``, ``{"op": "set_home", "drone"}``
- ``{"op": "home", "drone", "altitude_m"}``: fly home around obstacles, then land there
- ``{"op": "charge", "drone", "station"}``: fly to the station, land on it, charge
- ``{"op": "message", "drone", "to", "text"}``, ``{"op": "broadcast", "drone", "text"}``
- ``{"op": "reach", "drone", "target", "altitude_m"}``: fly over the target
- ``{"op": "sweep", "drones": [...], "target", "altitude_m"}``: cover an area target together
- ``{"op": "visit_targets", "drones": [...], "targets": [...], "altitude_m"}``: share the
  targets out and reach each one
- ``{"op": "track", "drone", "target", "duration_s", "altitude_m"}``: meet a moving target
  where it will be and follow it for duration_s
- ``{"op": "intercept", "drone", "target", "zone": [x, y, radius], "altitude_m"}``: meet a
  moving target at a time it is inside the zone
- ``{"op": "photo_target", "drone", "target", "altitude_m"}``: meet a moving target and
  photograph it
- ``{"op": "until_fault", "drone", "altitude_m", "duration_s"}``: take off and hold there
  while the task's hidden faults strike the drone; whatever outcome the fault gives ends it

A template may also schedule hidden faults (``TaskDraft.faults``, benchmark.authoring.task_faults):
the
agent is not told, and the oracle plan, written knowing them, works around them.
"""

from __future__ import annotations

import itertools
import math
import random
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import shapely

from emulator.scenario import Scenario, VehicleSpec
from emulator.world import Target

__all__ = [
    "CATEGORIES",
    "SessionView",
    "TaskDraft",
    "Template",
    "TemplateUnfit",
    "all_of",
    "fmt_xy",
    "leaf",
    "pick",
    "tour_length",
]

CATEGORIES = ("basic_operations", "navigation", "search", "multi_drone_coordination",
              "delivery", "communication", "battery_management", "target_tracking",
              "resilience")


class TemplateUnfit(Exception):
    """Raised by a template's build when this session cannot host it (e.g. no free spot)."""


def leaf(endpoint: str, expect: bool = True, **parameters: Any) -> dict[str, Any]:
    """A check-tree leaf."""
    node: dict[str, Any] = {"endpoint": endpoint, "parameters": parameters}
    if not expect:
        node["expect"] = False
    return node


def all_of(*checks: dict[str, Any]) -> dict[str, Any]:
    return {"logic": "and", "checks": list(checks)}


@dataclass
class TaskDraft:
    """What a template builds: phrasings, hidden checks, hidden oracle plan, budget hints."""

    phrasings: list[str]
    checks: dict[str, Any]
    oracle: list[list[dict[str, Any]]]
    flight_m: float = 0.0  # rough flight distance of the plan (per drone, the longest)
    hover_s: float = 0.0  # time the plan spends hovering or charging on purpose
    steps: int = 4  # primitive calls of the plan (for the tool-call budget)
    faults: dict[str, Any] | None = None  # hidden faults (benchmark.authoring.task_faults), if any


@dataclass(frozen=True)
class Template:
    """A task template: needs are counted in the session before it is drawn."""

    key: str
    category: str
    difficulty: str  # easy | medium | hard (the template's own label)
    build: Callable[[SessionView, random.Random], TaskDraft]
    drones: int = 1
    area_targets: int = 0
    point_targets: int = 0
    stations: int = 0
    families: tuple[str, ...] = ()  # empty: every family
    moving_targets: int = 0
    levels: tuple[str, ...] = ()  # empty: every level (generation filters by it)

    def fits(self, view: SessionView) -> bool:
        return (len(view.drones) >= self.drones and len(view.areas) >= self.area_targets
                and len(view.points) >= self.point_targets
                and len(view.movers) >= self.moving_targets
                and len(view.stations) >= self.stations
                and (not self.families or view.family in self.families))


@dataclass
class SessionView:
    """A session's static facts, for templates: drones, targets by kind, free space."""

    family: str
    scenario: Scenario
    map_w_m: float
    map_h_m: float
    drones: list[VehicleSpec] = field(init=False)
    areas: list[Target] = field(init=False)
    points: list[Target] = field(init=False)
    movers: list[Target] = field(init=False)
    stations: list[Target] = field(init=False)

    def __post_init__(self) -> None:
        world = self.scenario.world
        self.drones = list(self.scenario.vehicles)
        self.areas = [t for t in world.targets if t.is_area]
        self.points = [t for t in world.targets if t.kind == "fixed"]
        self.movers = [t for t in world.targets if t.kind == "moving"]
        self.stations = [t for t in world.targets if t.is_charging_station]
        blocked = [o.footprint for o in world.obstacles]
        self._blocked = shapely.union_all(blocked) if blocked else shapely.Polygon()
        shapely.prepare(self._blocked)
        footprints = [t.geometry for t in world.targets]
        self._targets = shapely.union_all(footprints) if footprints else shapely.Polygon()
        shapely.prepare(self._targets)

    # ------------------------------------------------------------ sampling
    def free_point(self, rng: random.Random, *, clearance_m: float = 15.0,
                   region: tuple[float, float, float, float] | None = None,
                   avoid_targets: bool = True, tries: int = 400) -> tuple[float, float]:
        """A random point (whole metres) at least clearance_m from every obstacle, inside
        region (x0, y0, x1, y1; default the map less a 30 m margin), outside every target
        footprint by 5 m when avoid_targets."""
        x0, y0, x1, y1 = region or (30.0, 30.0, self.map_w_m - 30.0, self.map_h_m - 30.0)
        x0, y0 = max(x0, 20.0), max(y0, 20.0)
        x1, y1 = min(x1, self.map_w_m - 20.0), min(y1, self.map_h_m - 20.0)
        if x1 <= x0 or y1 <= y0:
            raise TemplateUnfit(f"empty region {region}")
        for _ in range(tries):
            x, y = float(round(rng.uniform(x0, x1))), float(round(rng.uniform(y0, y1)))
            if self.is_free(x, y, clearance_m=clearance_m, avoid_targets=avoid_targets):
                return x, y
        raise TemplateUnfit(f"no free point in {region}")

    def is_free(self, x: float, y: float, *, clearance_m: float = 15.0,
                avoid_targets: bool = True) -> bool:
        p = shapely.Point(x, y)
        if self._blocked.distance(p) < clearance_m:
            return False
        return not (avoid_targets and self._targets.distance(p) < 5.0)

    def clear_leg(self, a: Sequence[float], b: Sequence[float], z_m: float,
                  *, clearance_m: float = 8.0) -> bool:
        """A straight leg a -> b at z_m keeps clearance_m from every obstacle it could meet."""
        line = shapely.LineString([(a[0], a[1]), (b[0], b[1])])
        for obstacle in self.scenario.world.obstacles:
            blocks = obstacle.height_m == 0.0 or z_m <= obstacle.height_m + clearance_m
            if blocks and obstacle.footprint.distance(line) < clearance_m:
                return False
        return True

    def region(self, fx0: float, fy0: float, fx1: float, fy1: float
               ) -> tuple[float, float, float, float]:
        """A region given as fractions of the map."""
        return (fx0 * self.map_w_m, fy0 * self.map_h_m, fx1 * self.map_w_m, fy1 * self.map_h_m)

    def cruise_altitude(self, rng: random.Random, lo: int = 15, hi: int = 30) -> int:
        return rng.randint(lo, hi)


def pick(rng: random.Random, items: Sequence[Any], k: int) -> list[Any]:
    """k distinct items in random order."""
    return rng.sample(list(items), k)


def fmt_xy(x: float, y: float) -> str:
    return f"({x:.0f}, {y:.0f})"


def tour_length(points: Sequence[Sequence[float]]) -> float:
    return sum(math.dist(a[:2], b[:2]) for a, b in itertools.pairwise(points))
