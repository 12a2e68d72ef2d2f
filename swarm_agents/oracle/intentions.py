"""What a derived plan wants of each drone, gathered leaf by leaf, and how it becomes a plan
(the operations of `benchmark.authoring.templates.base`, plus ``meet``: fly to a moving target)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from emulator.scenario import Scenario, VehicleSpec
from emulator.world import Target

__all__ = ["DroneIntent", "Intentions", "Unplannable", "target_point"]

Op = dict[str, Any]
DEFAULT_ALTITUDE_M = 20.0
GROUND_Z_M = 0.5  # a visit at or below this height is a landing there
TEAM_LIMIT = 3  # drones drafted for a team job nobody was named for
TRACK_PROGRESS_S = 20.0  # following time for the tracking family's task progress
EXCURSION_EXTRA_M = 6.0
AIRBORNE_OPS = frozenset({"takeoff", "goto", "reach", "towards", "hover", "track", "intercept",
                          "photo_target", "meet", "path", "altitude", "rotate", "photo"})
GROUNDING_OPS = frozenset({"land", "home", "charge"})
NEEDS_AIR = frozenset({"hover", "towards", "rotate", "altitude", "photo"})


class Unplannable(Exception):
    """A leaf of a check tree the derived planner cannot satisfy."""

    def __init__(self, path: str, endpoint: str, reason: str) -> None:
        super().__init__(f"cannot plan {path} ({endpoint}): {reason}")
        self.path, self.endpoint, self.reason = path, endpoint, reason


def target_point(target: Target) -> tuple[float, float]:
    """Where to fly to be over a target: its centre, or a point inside a concave polygon."""
    if target.kind == "polygon":
        centroid = target.geometry.centroid
        p = centroid if target.geometry.contains(centroid) else (
            target.geometry.representative_point())
        return float(p.x), float(p.y)
    return float(target.position_m[0]), float(target.position_m[1])


@dataclass
class DroneIntent:
    """One drone's share of a task."""

    id: str
    xy: tuple[float, float]
    home: tuple[float, float]
    actions: list[Op] = field(default_factory=list)
    reached: set[str] = field(default_factory=set)
    takeoff_range: tuple[float, float | None] | None = None
    final_xy: tuple[float, float] | None = None
    final_z: float | None = None
    final_home: bool = False
    final_ground: bool = False
    must_air: bool = False
    final_alt: float | None = None
    min_final_alt: float = 0.0
    final_heading: float | None = None
    min_battery: float = 0.0
    end_station: str | None = None
    charge_path: str | None = None
    min_landings: int = 0
    min_path_m: float = 0.0
    min_photos: int = 0

    def act(self, op: Op) -> None:
        self.actions.append(op)

    def visit(self, x: float, y: float, z: float | None) -> None:
        if z is not None and z <= GROUND_Z_M:
            self.act({"op": "goto", "x": x, "y": y, "z": None})
            self.act({"op": "land"})
        else:
            self.act({"op": "goto", "x": x, "y": y, "z": z})

    def reach(self, target: str) -> None:
        if target not in self.reached:
            self.reached.add(target)
            self.act({"op": "reach", "target": target})

    def photograph(self, target: str) -> None:
        """A photo from over a fixed target: right after the drone's reach of it, if planned."""
        for k, op in enumerate(self.actions):
            if op["op"] == "reach" and op["target"] == target:
                if k + 1 < len(self.actions) and self.actions[k + 1].get("of") == target:
                    return
                self.actions.insert(k + 1, {"op": "photo", "of": target})
                return
        self.reach(target)
        self.act({"op": "photo", "of": target})

    def cruise_m(self, task_m: float | None) -> float:
        for op in self.actions:
            if op["op"] == "goto" and op["z"] is not None:
                return float(op["z"])
        if self.takeoff_range is not None:
            lo, hi = self.takeoff_range
            return (lo + hi) / 2.0 if hi is not None else max(lo + 0.5, task_m or lo + 0.5)
        return max(task_m or DEFAULT_ALTITUDE_M, self.min_final_alt)


class Intentions:
    """Every drone's intentions for one task, and the team jobs."""

    def __init__(self, scenario: Scenario, drones: Mapping[str, Mapping[str, Any]],
                 faulted: set[str], named: set[str]) -> None:
        self.scenario = scenario
        self.world = scenario.world
        self.faulted = faulted
        self.named = [v.id for v in scenario.vehicles if v.id in named]
        self._vehicles = {v.id: v for v in scenario.vehicles}
        self._drones: dict[str, DroneIntent] = {}
        for v in scenario.vehicles:
            row = drones.get(v.id, {})
            xy = (float(row.get("x_m", v.position_m[0])), float(row.get("y_m", v.position_m[1])))
            home = (float(row.get("home_x_m", v.home_m[0])),
                    float(row.get("home_y_m", v.home_m[1])))
            self._drones[v.id] = DroneIntent(v.id, xy, home)
        self.spacing: list[tuple[str, list[str], float, float | None, str]] = []
        self.reach_any: list[tuple[str, str, int]] = []
        self.tracks: list[tuple[str, str, str | None, float]] = []
        self.sweeps: list[tuple[str, str, float]] = []

    # ------------------------------------------------------------ lookups
    def drone(self, drone_id: str, path: str) -> DroneIntent:
        found = self._drones.get(drone_id)
        if found is None:
            raise Unplannable(path, "drone", f"drone {drone_id!r} is not in this session")
        return found

    def all_drones(self) -> list[DroneIntent]:
        return list(self._drones.values())

    def vehicle(self, drone_id: str) -> VehicleSpec:
        return self._vehicles[drone_id]

    def target(self, target_id: str, path: str) -> Target:
        try:
            return self.world.target(target_id)
        except KeyError:
            raise Unplannable(path, "target", f"target {target_id!r} is not in this world"
                              ) from None

    def team(self, near: tuple[float, float] | None = None) -> list[str]:
        """The drones named by the task and free of faults; else the nearest few."""
        named = [d for d in self.named if d not in self.faulted]
        if named:
            return named
        pool = [d for d in self._drones if d not in self.faulted] or list(self._drones)
        if near is not None:
            pool.sort(key=lambda d: math.dist(self._drones[d].xy, near))
        return pool[:TEAM_LIMIT]

    def beside_obstacle(self, obstacle_id: str, limit_m: float, path: str, endpoint: str
                        ) -> tuple[tuple[float, float], float | None]:
        found = [o for o in self.world.obstacles if o.id == obstacle_id]
        if not found:
            raise Unplannable(path, endpoint, f"obstacle {obstacle_id!r} is not in this world")
        obstacle = found[0]
        margin = self.world.safety_margin_m
        if obstacle.height_m > 0.0:  # above its roof the 2D distance is 0
            c = obstacle.footprint.representative_point()
            return (float(c.x), float(c.y)), obstacle.height_m + margin + 8.0
        stand_m = margin + 2.0
        if stand_m >= limit_m:
            raise Unplannable(path, endpoint, f"{limit_m:g} m from the obstacle is inside its "
                              f"{margin:g} m safety margin")
        ring = obstacle.footprint.buffer(min(stand_m + 1.0, limit_m - 0.5)).exterior
        for k in range(24):
            p = ring.interpolate(k / 24.0, normalized=True)
            if self.world.clearance_ok(p.x, p.y, DEFAULT_ALTITUDE_M):
                return (float(p.x), float(p.y)), None
        raise Unplannable(path, endpoint, "no free spot beside the obstacle")

    # ------------------------------------------------------------ team jobs
    def sweep_target(self, path: str, target_id: str, threshold: float) -> None:
        target = self.target(target_id, path)
        if not target.is_area:
            self.reach_any.append((path, target.id, 1))
        else:
            self.sweeps.append((path, target.id, threshold))

    def whole_task(self, path: str) -> None:
        """task_progress / task_done: the scenario's own task, on every counted target."""
        counted = [t for t in self.world.targets if not t.is_charging_station]
        if not counted:
            raise Unplannable(path, "task_progress", "the world has no targets to work on")
        tracking = self.scenario.task_type == "target_tracking"
        for t in counted:
            if t.is_area:
                self.sweeps.append((path, t.id, 1.0))
            elif t.is_moving and tracking:
                self.tracks.append((path, t.id, None, TRACK_PROGRESS_S))
            else:
                self.reach_any.append((path, t.id, 1))

    def plan(self) -> list[list[Op]]:
        from swarm_agents.oracle.assemble import assemble
        return assemble(self)
