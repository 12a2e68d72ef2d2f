"""Moving targets' kinematics with MultiUAV-Plat's rules (../shared/spec/entities.md 3.3), in
simulated time.

Mode: **velocity** when some velocity component exceeds 1e-9 m/s and `moving_duration` > 0;
else **path** when the path has >= 2 points, a length > 0 and the duration is > 0 (speed =
path length / duration); else **stationary**.

- velocity: the target moves at its velocity; after `duration_s` in one direction the
  velocity is negated (ping-pong), and the time in that direction starts again;
- path: from its position it heads for the first path point, then along the path at the
  path's speed, bouncing at both ends;
- obstacles: a target about to enter an obstacle (its raw footprint, at the target's
  altitude) turns round where it meets it; in velocity mode the time in the new direction
  starts again, in path mode it heads back to the point it came from.

The motion is piecewise linear and decided by the start alone, so it is held as *legs* (start
time, start point, velocity), built lazily in continuous simulated time. The fleet advances
the targets with every physics step (:meth:`MovingTargets.advance`), and positions at any
instant, breakpoints and predictions are exact (no wall clock, no I/O).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import shapely

__all__ = ["EPS_SPEED_M_S", "LOOKAHEAD_S", "MOTION_MODES", "EntryFn", "MotionSpec",
           "MovingTargets", "TargetLegs", "motion_spec", "moving_targets_of", "obstacle_entry"]

MOTION_MODES = ("velocity", "path", "stationary")
EPS_SPEED_M_S = 1e-9
LOOKAHEAD_S = 120.0  # legs are built this far past the latest instant asked for
_BACKOFF_M = 1e-6  # a target turning at an obstacle stops this far before its footprint
_MAX_LEGS_PER_EXTEND = 100_000

Point3 = tuple[float, float, float]
EntryFn = Callable[[np.ndarray, np.ndarray], float | None]


@dataclass(frozen=True, slots=True)
class MotionSpec:
    """How one target moves: its mode, start, velocity or path, and duration."""

    mode: str
    start_m: Point3
    velocity_m_s: Point3 = (0.0, 0.0, 0.0)
    path_m: tuple[Point3, ...] = ()
    duration_s: float = 10.0

    def __post_init__(self) -> None:
        if self.mode not in MOTION_MODES:
            raise ValueError(f"motion mode must be one of {MOTION_MODES}, got {self.mode!r}")

    @property
    def speed_m_s(self) -> float:
        if self.mode == "velocity":
            return math.hypot(*self.velocity_m_s)
        if self.mode == "path":
            return _path_length(self.path_m) / self.duration_s
        return 0.0


def _path_length(path: Sequence[Sequence[float]]) -> float:
    return sum(math.dist(a, b) for a, b in itertools.pairwise(path))


def motion_spec(start_m: Sequence[float], velocity_m_s: Sequence[float] | None,
                path_m: Sequence[Sequence[float]] | None, duration_s: float) -> MotionSpec:
    """The motion of a `moving` target, by the reference's mode priority."""
    start = (float(start_m[0]), float(start_m[1]), float(start_m[2]))
    v = tuple(float(c) for c in velocity_m_s) if velocity_m_s is not None else (0.0, 0.0, 0.0)
    path = tuple((float(p[0]), float(p[1]), float(p[2])) for p in path_m or ())
    if duration_s > 0.0 and any(abs(c) > EPS_SPEED_M_S for c in v):
        return MotionSpec("velocity", start, (v[0], v[1], v[2]), path, float(duration_s))
    if duration_s > 0.0 and len(path) >= 2 and _path_length(path) > 0.0:
        return MotionSpec("path", start, (0.0, 0.0, 0.0), path, float(duration_s))
    return MotionSpec("stationary", start, (0.0, 0.0, 0.0), path, max(float(duration_s), 0.0))


def obstacle_entry(obstacles: Sequence[object]) -> EntryFn:
    """A function (a, b) -> the fraction of the straight move a -> b at which it first enters
    an obstacle's raw footprint at an altitude the obstacle occupies, or None. Obstacles that
    already hold `a` are left alone (a target inside one may leave it). `obstacles` are
    `emulator.world.Obstacle`s (footprint, blocks_altitude)."""
    items: list[tuple[Any, Any]] = [(o.footprint, o) for o in obstacles]  # type: ignore[attr-defined]
    # Footprint bounds (minx, miny, maxx, maxy): a footprint whose box misses the move's box
    # neither holds `a` nor meets the move, so only the others are tested one by one.
    bounds = shapely.bounds(np.array([f for f, _ in items], dtype=object)).reshape(-1, 4)

    def entry(a: np.ndarray, b: np.ndarray) -> float | None:
        if not items or np.allclose(a[:2], b[:2]):
            return None
        x0, x1 = (a[0], b[0]) if a[0] <= b[0] else (b[0], a[0])
        y0, y1 = (a[1], b[1]) if a[1] <= b[1] else (b[1], a[1])
        near = np.flatnonzero((bounds[:, 0] <= x1) & (bounds[:, 2] >= x0)
                              & (bounds[:, 1] <= y1) & (bounds[:, 3] >= y0))
        if near.size == 0:
            return None
        line = shapely.LineString([a[:2], b[:2]])
        length = line.length
        best: float | None = None
        for i in near.tolist():
            footprint, obstacle = items[i]
            if not obstacle.blocks_altitude(float(max(a[2], b[2]))):
                continue
            if shapely.intersects_xy(footprint, float(a[0]), float(a[1])):
                continue
            if not line.intersects(footprint):
                continue
            hit = line.intersection(footprint)
            coords = shapely.get_coordinates(hit)
            f = min(line.project(shapely.Point(c)) for c in coords) / length
            if best is None or f < best:
                best = f
        return best
    return entry


class TargetLegs:
    """One target's motion as legs, extended on demand."""

    def __init__(self, spec: MotionSpec, entry: EntryFn | None = None) -> None:
        self.spec = spec
        self._entry = entry or (lambda a, b: None)
        start = np.array(spec.start_m, dtype=float)
        self._t: list[float] = []
        self._p: list[np.ndarray] = []
        self._v: list[np.ndarray] = []
        self._arrays: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        # Where the next leg starts, and the mode's state there.
        self._now_t, self._now_p = 0.0, start
        self._vel = np.array(spec.velocity_m_s, dtype=float)
        self._index, self._dir = 0, 1
        self._blocked_in_a_row = 0
        self._still = spec.mode == "stationary"
        self._path = np.array(spec.path_m, dtype=float).reshape(-1, 3)
        self._speed = spec.speed_m_s

    @property
    def built_until_s(self) -> float:
        return math.inf if self._still and self._t else self._now_t

    def _add(self, t: float, p: np.ndarray, v: np.ndarray) -> None:
        self._t.append(t)
        self._p.append(p.copy())
        self._v.append(v.copy())
        self._arrays = None

    def _stand(self) -> None:
        self._add(self._now_t, self._now_p, np.zeros(3))
        self._still = True

    def extend(self, until_s: float) -> None:
        """Build legs until they cover [0, until_s]."""
        built = 0
        while not self._still and self._now_t <= until_s and built < _MAX_LEGS_PER_EXTEND:
            built += 1
            if self.spec.mode == "velocity":
                self._velocity_leg()
            else:
                self._path_leg()
        if self._still and not self._t:
            self._stand()

    def _move(self, goal: np.ndarray, duration_s: float) -> bool:
        """Add a leg towards goal lasting duration_s; False if an obstacle turned it round."""
        a = self._now_p
        f = self._entry(a, goal)
        v = (goal - a) / duration_s
        if f is None:
            self._add(self._now_t, a, v)
            self._now_t += duration_s
            self._now_p = goal.copy()
            self._blocked_in_a_row = 0
            return True
        length = float(np.linalg.norm(goal - a))
        f = max(f - _BACKOFF_M / length, 0.0) if length > 0.0 else 0.0
        if f * duration_s > 1e-9:
            self._add(self._now_t, a, v)
            self._now_t += f * duration_s
            self._now_p = a + (goal - a) * f
            self._blocked_in_a_row = 0
        else:
            self._blocked_in_a_row += 1
        return False

    def _velocity_leg(self) -> None:
        d = self.spec.duration_s
        self._move(self._now_p + self._vel * d, d)
        self._vel = -self._vel
        if self._blocked_in_a_row >= 2:  # boxed in both ways: it stands
            self._stand()

    def _path_leg(self) -> None:
        n = self._path.shape[0]
        goal = self._path[self._index]
        length = float(np.linalg.norm(goal - self._now_p))
        arrived = True
        if length > 0.0:
            arrived = self._move(goal, length / self._speed)
        if arrived:
            nxt = self._index + self._dir
            if not 0 <= nxt < n:
                self._dir = -self._dir
                nxt = self._index + self._dir
            self._index = nxt
        else:
            self._dir = -self._dir
            self._index = min(max(self._index + self._dir, 0), n - 1)
            if self._blocked_in_a_row >= 2:
                self._stand()

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Leg start times (L,), start points (L, 3) and velocities (L, 3)."""
        if self._arrays is None:
            self._arrays = (np.array(self._t), np.array(self._p).reshape(-1, 3),
                            np.array(self._v).reshape(-1, 3))
        return self._arrays

    def positions(self, times_s: np.ndarray) -> np.ndarray:
        """Positions (K, 3) at the given times (>= 0), legs built as needed."""
        times = np.asarray(times_s, dtype=float).reshape(-1)
        if times.size:
            self.extend(float(times.max()))
        t0, p0, v = self.arrays()
        k = np.clip(np.searchsorted(t0, times, side="right") - 1, 0, None)
        return p0[k] + v[k] * np.maximum(times - t0[k], 0.0)[:, None]

    def rows(self, t0_s: float, t1_s: float) -> np.ndarray:
        """(t, x, y, z) rows over [t0_s, t1_s]: both ends and every leg start between, so that
        linear interpolation between rows is the exact motion."""
        t0, t1 = max(float(t0_s), 0.0), max(float(t1_s), 0.0)
        self.extend(t1)
        starts = self.arrays()[0]
        inner = starts[(starts > t0) & (starts < t1)]
        times = np.unique(np.concatenate(([t0], inner, [t1])))
        return np.column_stack((times, self.positions(times)))


class MovingTargets:
    """Every moving target of a world, advanced together by the physics step."""

    def __init__(self, ids: Sequence[str], specs: Sequence[MotionSpec],
                 entry: EntryFn | None = None) -> None:
        self.ids = tuple(ids)
        self._legs = [TargetLegs(s, entry) for s in specs]
        self._index = {ident: k for k, ident in enumerate(self.ids)}
        m = len(self._legs)
        # Each target's leg at the latest instant asked for: positions there are one
        # vectorised expression until some target's next leg starts.
        self._leg_t0, self._leg_next_t = np.zeros(m), np.full(m, -np.inf)
        self._leg_p0, self._leg_v = np.zeros((m, 3)), np.zeros((m, 3))
        self._fresh_from, self._fresh_until = math.inf, -math.inf
        self.now_s = 0.0
        self._position_m: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.ids)

    def legs(self, target_id: str) -> TargetLegs:
        return self._legs[self._index[target_id]]

    def _refresh(self, t_s: float, stale: np.ndarray) -> None:
        for k in np.flatnonzero(stale):
            legs = self._legs[k]
            if legs.built_until_s <= t_s:
                legs.extend(t_s + LOOKAHEAD_S)
            t0, p0, v = legs.arrays()
            i = max(int(np.searchsorted(t0, t_s, side="right")) - 1, 0)
            self._leg_t0[k], self._leg_p0[k], self._leg_v[k] = t0[i], p0[i], v[i]
            self._leg_next_t[k] = t0[i + 1] if i + 1 < t0.size else legs.built_until_s
        if self._legs:
            self._fresh_from = float(self._leg_t0.max())
            self._fresh_until = float(self._leg_next_t.min())

    def positions_at(self, t_s: float) -> np.ndarray:
        """Every target's position (M, 3) at t_s."""
        t = float(t_s)
        if not self._fresh_from <= t < self._fresh_until:
            stale = (t < self._leg_t0) | (t >= self._leg_next_t)
            if stale.any():
                self._refresh(t, stale)
        return self._leg_p0 + self._leg_v * np.maximum(t - self._leg_t0, 0.0)[:, None]

    def advance(self, now_s: float, dt_s: float) -> None:
        """One physics step (or dt_s of them) from now_s: the positions at now_s + dt_s
        become the current ones (worked out when first read: the motion is a function of
        time alone)."""
        self.now_s = now_s + dt_s
        self._position_m = None

    @property
    def position_m(self) -> np.ndarray:
        """Every target's position (M, 3) at `now_s`."""
        if self._position_m is None:
            self._position_m = self.positions_at(self.now_s)
        return self._position_m

    def current(self) -> dict[str, Point3]:
        """The current position of each target, by id."""
        return {ident: (float(p[0]), float(p[1]), float(p[2]))
                for ident, p in zip(self.ids, self.position_m, strict=True)}

    def rows(self, target_id: str, t0_s: float, t1_s: float) -> np.ndarray:
        """Exact (t, x, y, z) rows of one target over [t0_s, t1_s] (see TargetLegs.rows)."""
        return self.legs(target_id).rows(t0_s, t1_s)


def moving_targets_of(targets: Sequence[object], obstacles: Sequence[object]
                      ) -> MovingTargets | None:
    """The `moving` targets of a world (`emulator.world.Target`s) with their motion, or None
    when there are none. A moving target without a motion stands where it is."""
    ids: list[str] = []
    specs: list[MotionSpec] = []
    for t in targets:
        if getattr(t, "kind", None) != "moving":
            continue
        ids.append(t.id)  # type: ignore[attr-defined]
        spec = t.motion or MotionSpec("stationary", t.position_m)  # type: ignore[attr-defined]
        specs.append(spec)
    if not ids:
        return None
    return MovingTargets(ids, specs, obstacle_entry(obstacles))
