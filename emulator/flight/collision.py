"""Collision prevention's safety net: no vehicle ever enters an obstacle volume.

Goals are already cut short at the safety margin when they are set (World.first_blockage);
this guard covers what a straight-line check cannot (curved paths when a goal changes in
flight, velocity set-points, wind drift). It is cheap because it is lazy: after measuring a
vehicle's clearance D to the nearest obstacle volume, the vehicle cannot reach any obstacle
before D / v_max seconds, so it is not looked at again until then.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import shapely

from emulator.world import World

__all__ = ["FEW_OBSTACLES", "ClearanceGuard"]

# Up to this many obstacles the boxes are looked at in Python floats; with more, numpy's
# passes over whole arrays cost less.
FEW_OBSTACLES = 16


class ClearanceGuard:
    """Per-vehicle clearance bookkeeping for one world."""

    def __init__(self, world: World, n: int) -> None:
        obstacles = world.obstacles
        self.enabled = bool(obstacles)
        self._footprints = np.array([o.footprint for o in obstacles], dtype=object)
        self._heights = np.array([o.height_m for o in obstacles], dtype=float)
        self._capped = self._heights > 0.0
        # The height above which a volume lies below a point (an uncapped one never does).
        self._top_m = np.where(self._capped, self._heights, np.inf)
        # Footprint bounds (minx, miny, maxx, maxy): the distance to a footprint's box is a
        # lower bound of the distance to the footprint.
        self._bounds = np.nan_to_num(shapely.bounds(self._footprints).reshape(-1, 4),
                                     nan=np.inf)
        if self.enabled:
            shapely.prepare(self._footprints)
        # The same bounds and tops as Python floats, for a world of a few obstacles (None: more).
        self._boxes: list[tuple[float, float, float, float, float]] | None = None
        if len(obstacles) <= FEW_OBSTACLES:
            self._boxes = [(x0, y0, x1, y1, top) for (x0, y0, x1, y1), top
                           in zip(self._bounds.tolist(), self._top_m.tolist(), strict=True)]
        self.check_at_s = np.zeros(n)
        self._first_check_s = 0.0  # the earliest of check_at_s (kept by the methods below)

    def clearance_m(self, x_m: float, y_m: float, z_m: float) -> float:
        """Distance from a point to the nearest obstacle volume (0 when inside one)."""
        if not self.enabled:
            return math.inf
        # Only the volumes whose boxes lie no farther than the one nearest by box are measured
        # exactly: the same minimum as measuring all (the others are provably farther).
        if self._boxes is not None:
            return self._clearance_of_few(self._boxes, x_m, y_m, z_m)
        b = self._bounds
        dx = np.maximum(np.maximum(b[:, 0] - x_m, x_m - b[:, 2]), 0.0)
        dy = np.maximum(np.maximum(b[:, 1] - y_m, y_m - b[:, 3]), 0.0)
        above = np.maximum(0.0, z_m - self._top_m)
        low_sq = dx * dx + dy * dy + above * above
        point = shapely.Point(x_m, y_m)
        first = int(low_sq.argmin())
        d0 = float(shapely.distance(self._footprints[first], point))
        a0 = float(above[first])
        near = np.flatnonzero(low_sq <= (d0 * d0 + a0 * a0) * (1.0 + 1e-9) + 1e-9)
        if near.size == 1:  # the nearest by box alone: measured already
            return math.sqrt(d0 * d0 + a0 * a0)
        d_xy = shapely.distance(self._footprints[near], point)
        up = above[near]
        return float(np.sqrt(d_xy * d_xy + up * up).min())

    def _clearance_of_few(self, boxes: list[tuple[float, float, float, float, float]],
                          x_m: float, y_m: float, z_m: float) -> float:
        """`clearance_m` in Python floats, obstacle by obstacle (cheaper for a few): the same
        operations, so the same result to the last bit."""
        lows: list[float] = []
        aboves: list[float] = []
        first, first_low = 0, math.inf
        for i, (x0, y0, x1, y1, top) in enumerate(boxes):
            dx = max(x0 - x_m, x_m - x1, 0.0)
            dy = max(y0 - y_m, y_m - y1, 0.0)
            above = z_m - top
            if not above > 0.0:
                above = 0.0
            low = dx * dx + dy * dy + above * above
            if low < first_low:
                first, first_low = i, low
            lows.append(low)
            aboves.append(above)
        point = shapely.Point(x_m, y_m)
        footprints = self._footprints
        # a geometry's own `distance`: GEOS's distance without the array function's overhead
        d0 = float(footprints[first].distance(point))
        a0 = aboves[first]
        best = math.sqrt(d0 * d0 + a0 * a0)
        limit = (d0 * d0 + a0 * a0) * (1.0 + 1e-9) + 1e-9
        for i, low in enumerate(lows):
            if i != first and low <= limit:
                d = float(footprints[i].distance(point))
                best = min(best, math.sqrt(d * d + aboves[i] * aboves[i]))
        return best

    def forget(self, k: int) -> None:
        """Force a fresh check of vehicle k (its motion limits changed)."""
        self.check_at_s[k] = 0.0
        self._first_check_s = 0.0

    def due(self, now_s: float, active: np.ndarray) -> np.ndarray | None:
        """Mask of the `active` vehicles whose clearance deadline has passed at now_s (None
        when there is none: no vehicle needs a look)."""
        if not self.enabled or now_s < self._first_check_s:
            return None
        due = active & (self.check_at_s <= now_s)
        return due if np.count_nonzero(due) else None

    def check(self, now_s: float, candidates: np.ndarray, new_pos: np.ndarray,
              max_speed_m_s: Callable[[int], float], dt_s: float) -> np.ndarray:
        """Indices among `candidates` whose new position lies inside an obstacle.

        Vehicles whose clearance deadline has passed are measured at `new_pos`; the rest
        provably cannot have reached an obstacle yet.
        """
        if not self.enabled or candidates.size == 0:
            return candidates[:0]
        due = candidates[self.check_at_s[candidates] <= now_s]
        if due.size == 0:
            return due
        hits = []
        for k in due:
            x, y, z = new_pos[k]
            if self._measure(int(k), now_s, float(x), float(y), float(z), max_speed_m_s(int(k)),
                             dt_s):
                hits.append(k)
        self._first_check_s = float(self.check_at_s.min())
        return np.asarray(hits, dtype=np.intp)

    def check_one(self, k: int, now_s: float, x_m: float, y_m: float, z_m: float,
                  max_speed_m_s: float, dt_s: float) -> bool:
        """`check` for vehicle k alone, moving to (x_m, y_m, z_m): whether that lies inside
        an obstacle (False while its clearance deadline lies ahead)."""
        if not self.enabled or self.check_at_s[k] > now_s:
            return False
        hit = self._measure(k, now_s, x_m, y_m, z_m, max_speed_m_s, dt_s)
        self._first_check_s = float(self.check_at_s.min())
        return hit

    def _measure(self, k: int, now_s: float, x_m: float, y_m: float, z_m: float,
                 max_speed_m_s: float, dt_s: float) -> bool:
        clearance = self.clearance_m(x_m, y_m, z_m)
        if clearance <= 0.0:
            self.check_at_s[k] = 0.0
            return True
        # Travel time to the nearest volume, less one step of slack.
        self.check_at_s[k] = now_s + max(0.0, clearance / max(max_speed_m_s, 0.1) - dt_s)
        return False
