"""Intentions to a three-phase plan: (1) take-offs and each drone's own actions, (2) team jobs
(area sweeps, targets shared out, tracking), (3) charging and end states."""

from __future__ import annotations

import math
from typing import Any

from swarm_agents.oracle.intentions import (
    AIRBORNE_OPS,
    EXCURSION_EXTRA_M,
    GROUNDING_OPS,
    NEEDS_AIR,
    DroneIntent,
    Intentions,
    Unplannable,
    target_point,
)

__all__ = ["assemble"]

Op = dict[str, Any]
HOME_TOLERANCE_M = 2.0
# A drone whose plan flies further than a battery surely carries it (one lasts 4-7 km at cruise
# speed, less with wind, climbs and detours) charges on the way, before its flight since the last
# charge plus the way on to a station would pass RANGE_M.
LONG_FLIGHT_M = 4500.0
RANGE_M = 2500.0
SPACING_DIRECTIONS = 16


class _Flight:
    """A drone's simulated plan: airborne or not, where it is, how far it flew, landings."""

    def __init__(self, it: Intentions, d: DroneIntent, cruise_m: float,
                 range_m: float | None = None) -> None:
        self.it, self.d, self.cruise_m = it, d, cruise_m
        self.range_m = range_m
        self.since_charge_m = 0.0
        self.air = False
        self.xy = d.xy
        self.z = 0.0
        self.flown_m = 0.0
        self.landings = 0
        self.photos = 0
        self.home = d.home
        self.ops: list[Op] = []

    def emit(self, op: Op) -> None:
        kind = op["op"]
        if kind in NEEDS_AIR and not self.air:
            self.emit({"op": "takeoff", "altitude_m": self.cruise_m})
        op = {**{k: v for k, v in op.items() if k != "of"}, "drone": self.d.id}
        if self.range_m is not None and kind in ("goto", "reach", "photo_target"):
            self._charge_before(op)
        if kind == "goto":
            op["z"] = self.cruise_m if op["z"] is None else float(op["z"])
            self._move((float(op["x"]), float(op["y"])), op["z"])
        elif kind in ("reach", "photo_target", "intercept", "meet", "track"):
            op["altitude_m"] = self.cruise_m
            target = self.it.world.target(op["target"])
            if not target.is_moving:
                self._move(target_point(target), self.cruise_m)
        elif kind == "towards":
            h = math.radians(float(op["heading_deg"]))
            dist = float(op["distance_m"])
            self._move((self.xy[0] + dist * math.sin(h), self.xy[1] + dist * math.cos(h)),
                       self.z or self.cruise_m)
        elif kind == "takeoff" or kind == "altitude":
            self.z = float(op["altitude_m"])
        elif kind == "home":
            op["altitude_m"] = self.cruise_m
            self._move(self.home, self.cruise_m)
        elif kind == "set_home":
            self.home = self.xy
        elif kind == "charge":
            station = self.it.world.target(op["station"])
            self._move(target_point(station), self.cruise_m)
        if kind in ("photo", "photo_target"):
            self.photos += 1
        if kind in GROUNDING_OPS:
            self.air, self.z = False, 0.0
            self.landings += 1
        elif kind in AIRBORNE_OPS:
            self.air = True
        self.ops.append(op)

    def _move(self, xy: tuple[float, float], z: float) -> None:
        self.flown_m += math.dist(self.xy, xy)
        self.since_charge_m += math.dist(self.xy, xy)
        self.xy, self.z = xy, z

    def _charge_before(self, op: Op) -> None:
        """A charge first when this leg and the way on to a station would pass range_m."""
        assert self.range_m is not None
        if op["op"] == "goto":
            goal = (float(op["x"]), float(op["y"]))
        else:
            target = self.it.world.target(op["target"])
            if target.is_moving:
                return
            goal = target_point(target)
        stations = [t for t in self.it.world.targets if t.is_charging_station]
        if not stations:
            return
        onward = min(math.dist(goal, target_point(t)) for t in stations)
        if self.since_charge_m + math.dist(self.xy, goal) + onward > self.range_m:
            here = min(stations, key=lambda t: math.dist(target_point(t), self.xy))
            self.emit({"op": "charge", "station": here.id})
            self.since_charge_m = 0.0


def _takeoff_m(d: DroneIntent, cruise_m: float) -> float | None:
    if d.takeoff_range is None:
        return None
    lo, hi = d.takeoff_range
    return (lo + hi) / 2.0 if hi is not None else max(lo + 0.5, cruise_m)


def _task_altitude(it: Intentions) -> float | None:
    for d in it.all_drones():
        for op in d.actions:
            if op["op"] == "goto" and op["z"] is not None:
                return float(op["z"])
    for d in it.all_drones():
        if d.takeoff_range is not None:
            return d.takeoff_range[0] + 0.5
    return None


def _nearest_station(it: Intentions, xy: tuple[float, float], path: str) -> str:
    stations = [t for t in it.world.targets if t.is_charging_station]
    if not stations:
        raise Unplannable(path, "drone_has_charged", "the world has no charging station")
    return min(stations, key=lambda t: math.dist(target_point(t), xy)).id


def _share_team_jobs(it: Intentions) -> list[Op]:
    """Sweeps and targets reached by any drone become team operations; tracking becomes
    each chosen drone's action."""
    team_ops: list[Op] = []
    swept: dict[str, list[str]] = {}
    areas = [t for _, t, _ in it.sweeps]
    areas = list(dict.fromkeys(areas))
    if areas:
        first = target_point(it.world.target(areas[0]))
        team = it.team(first)
        if len(team) >= len(areas):
            for k, drone in enumerate(team):
                swept.setdefault(areas[k % len(areas)], []).append(drone)
        else:
            for k, area in enumerate(areas):
                swept[area] = [team[k % len(team)]]
        for area, drones in swept.items():
            team_ops.append({"op": "sweep", "drones": drones, "target": area})
    loose: list[str] = []
    for path, target_id, count in it.reach_any:
        target = it.world.target(target_id)
        point = target_point(target)
        have = {d.id for d in it.all_drones() if target_id in d.reached}
        have |= set(swept.get(target_id, []))
        need = count - len(have)
        if need <= 0:
            continue
        if count == 1 and not target.is_moving:
            loose.append(target_id)
            continue
        pool = [d for d in it.team(point) if d not in have]
        pool += [d.id for d in it.all_drones()
                 if d.id not in have and d.id not in pool and d.id not in it.faulted]
        pool.sort(key=lambda d: math.dist(it.drone(d, path).xy, point))
        if len(pool) < need:
            raise Unplannable(path, "target_reached_drone_number",
                              f"{count} drones must reach {target_id}, only "
                              f"{len(pool) + len(have)} can")
        for drone in pool[:need]:
            d = it.drone(drone, path)
            d.reached.add(target_id)
            d.act({"op": "meet" if target.is_moving else "reach", "target": target_id})
    if loose:
        loose = list(dict.fromkeys(loose))
        centre = target_point(it.world.target(loose[0]))
        team_ops.append({"op": "visit_targets", "drones": it.team(centre), "targets": loose})
    busy: set[str] = set()
    for path, target_id, named, duration in it.tracks:
        chosen = named
        if chosen is None:
            point = target_point(it.world.target(target_id))
            pool = [d for d in it.team(point) if d not in busy] or it.team(point)
            pool.sort(key=lambda d: math.dist(it.drone(d, path).xy, point))
            chosen = pool[0]
        busy.add(chosen)
        it.drone(chosen, path).act({"op": "track", "target": target_id, "duration_s": duration})
    return team_ops


def _free_near(it: Intentions, xy: tuple[float, float], z: float, dist_m: float
               ) -> tuple[float, float] | None:
    for k in range(SPACING_DIRECTIONS):
        a = 2.0 * math.pi * k / SPACING_DIRECTIONS
        p = (xy[0] + dist_m * math.cos(a), xy[1] + dist_m * math.sin(a))
        if it.world.clearance_ok(p[0], p[1], z) and it.world.clearance_ok(p[0], p[1], 40.0):
            return p
    return None


def _end_xyz(f: _Flight) -> tuple[float, float, float]:
    d = f.d
    xy = d.final_xy or (d.home if d.final_home else f.xy)
    if d.final_ground:
        return (*xy, 0.0)
    z = d.final_z or d.final_alt or (f.z if f.air or d.must_air else 0.0)
    return (*xy, max(z or 0.0, d.min_final_alt) or (f.cruise_m if d.must_air else 0.0))


def _space_out(it: Intentions, flights: dict[str, _Flight]) -> None:
    """Give drones without a fixed end spot one that meets the distance checks."""
    for path, drones, lo, hi, mode in it.spacing:
        fixed = [d for d in drones if flights[d].d.final_xy is not None]
        anchor = fixed[0] if fixed else drones[0]
        a = _end_xyz(flights[anchor])
        for other in drones:
            if other == anchor:
                continue
            f = flights[other]
            b = _end_xyz(f)
            dist = math.dist(a, b)
            if dist >= lo and (hi is None or dist <= hi):
                continue
            if f.d.final_xy is not None and mode == "all_pairs":
                raise Unplannable(path, "two_drones_distance", f"{anchor} and {other} must end "
                                  f"{dist:.0f} m apart")
            want = lo + 3.0 if hi is None else max(lo + 0.5 * (float(hi) - lo), min(
                float(hi) * 0.5, lo + 5.0))
            z = a[2] if a[2] > 0 else f.cruise_m
            spot = _free_near(it, a[:2], z, math.sqrt(max(want ** 2 - (z - a[2]) ** 2, 1.0)))
            if spot is None:
                raise Unplannable(path, "two_drones_distance", "no free spot at that distance")
            f.d.final_xy = spot
            f.d.final_z = z if a[2] > 0 or f.d.must_air else None
            if a[2] <= 0.0 and not f.d.must_air:
                f.d.final_ground = True
            if mode == "any_pair":
                break


def _excursion(it: Intentions, f: _Flight, need_m: float) -> None:
    """Fly out and back to make up the distance a drone_has_moved_distance check wants."""
    leg = need_m / 2.0 + EXCURSION_EXTRA_M
    z = f.z if f.air else f.cruise_m
    for k in range(SPACING_DIRECTIONS):
        a = 2.0 * math.pi * k / SPACING_DIRECTIONS
        p = (f.xy[0] + leg * math.cos(a), f.xy[1] + leg * math.sin(a), z)
        if it.world.first_blockage((*f.xy, z), p) is None:
            back = f.xy
            f.emit({"op": "goto", "x": p[0], "y": p[1], "z": z})
            f.emit({"op": "goto", "x": back[0], "y": back[1], "z": z})
            return
    raise Unplannable("checks", "drone_has_moved_distance", "no open line to fly along")


def _finish(it: Intentions, f: _Flight) -> None:
    d = f.d
    if d.charge_path is not None or d.end_station is not None or (
            d.min_battery >= 95.0 and f.flown_m > 0.0):
        station = d.end_station or _nearest_station(it, f.xy, d.charge_path or "checks")
        f.emit({"op": "charge", "station": station})
    if d.min_path_m > f.flown_m:
        end = d.final_xy or (f.home if d.final_home else f.xy)
        short = d.min_path_m - f.flown_m - math.dist(f.xy, end)
        if short > 0:
            _excursion(it, f, short)
    at_station = d.end_station is not None and d.final_xy is None
    if d.final_ground:
        if d.final_xy is not None:
            if d.final_home and math.dist(d.final_xy, f.home) <= HOME_TOLERANCE_M:
                f.emit({"op": "home"})
            else:
                f.emit({"op": "goto", "x": d.final_xy[0], "y": d.final_xy[1], "z": None})
                f.emit({"op": "land"})
        elif d.final_home and not at_station:
            f.emit({"op": "home"})
        elif f.air:
            f.emit({"op": "land"})
    else:
        z = d.final_z or d.final_alt
        if d.final_xy is None and d.final_home:
            d.final_xy = f.home
        if d.final_xy is not None:
            f.emit({"op": "goto", "x": d.final_xy[0], "y": d.final_xy[1],
                    "z": z if z is not None else max(f.cruise_m, d.min_final_alt)})
        elif d.must_air and not f.air:
            f.emit({"op": "takeoff", "altitude_m": z or max(f.cruise_m, d.min_final_alt)})
        if d.final_alt is not None and abs(f.z - d.final_alt) > 0.3:
            f.emit({"op": "altitude", "altitude_m": d.final_alt})
        elif d.min_final_alt > f.z and f.air:
            f.emit({"op": "altitude", "altitude_m": d.min_final_alt})
        if d.final_heading is not None:
            f.emit({"op": "rotate", "heading_deg": d.final_heading})
    _land_enough(f)


def _land_enough(f: _Flight) -> None:
    """Land (and take off again) until the plan makes the landings the checks count; a
    drone that must end in the air climbs back to where it was."""
    missing = f.d.min_landings - f.landings
    if missing <= 0:
        return
    was_air, z = f.air, f.z
    for _ in range(missing):
        if not f.air:
            f.emit({"op": "takeoff", "altitude_m": f.cruise_m})
        f.emit({"op": "land"})
    if was_air:
        f.emit({"op": "takeoff", "altitude_m": z})
        if f.d.final_heading is not None:
            f.emit({"op": "rotate", "heading_deg": f.d.final_heading})


def assemble(it: Intentions, ranged: frozenset[str] = frozenset()) -> list[list[Op]]:
    """The phases of the plan; drones in `ranged` stop to charge on long flights (a plan in
    which some drone flies further than LONG_FLIGHT_M is made again with them ranged)."""
    task_m = _task_altitude(it)
    team_ops = _share_team_jobs(it)
    flights = {d.id: _Flight(it, d, d.cruise_m(task_m), RANGE_M if d.id in ranged else None)
               for d in it.all_drones()}
    for op in team_ops:  # sweeps fly at the first swept drone's cruise altitude
        op["altitude_m"] = flights[op["drones"][0]].cruise_m
    first: list[Op] = []
    for d in it.all_drones():
        f = flights[d.id]
        # A new home: land on the end spot and make it home before the rest.
        if d.final_home and d.final_xy is not None and math.dist(d.final_xy, d.home) > 2.0:
            f.emit({"op": "goto", "x": d.final_xy[0], "y": d.final_xy[1], "z": None})
            f.emit({"op": "land"})
            f.emit({"op": "set_home"})
        takeoff = _takeoff_m(d, f.cruise_m)
        if takeoff is not None:
            f.emit({"op": "takeoff", "altitude_m": takeoff})
        for op in d.actions:
            f.emit(op)
        for _ in range(d.min_photos - f.photos):
            f.emit({"op": "photo"})
        first.extend(f.ops)
        f.ops = []
    for op in team_ops:
        for drone in op["drones"]:
            flights[drone].air = True
    _space_out(it, flights)
    last: list[Op] = []
    for d in it.all_drones():
        f = flights[d.id]
        _finish(it, f)
        last.extend(f.ops)
    long = frozenset(k for k, f in flights.items() if f.flown_m > LONG_FLIGHT_M)
    if long and not ranged and any(t.is_charging_station for t in it.world.targets):
        return assemble(it, long)
    return [phase for phase in (first, team_ops, last) if phase]
