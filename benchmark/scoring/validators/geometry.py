"""Vectorised planar geometry for the validators.

Target footprints of the disc kinds (fixed, moving, waypoint, circle) are measured as exact
circles of their radius; polygon targets and every obstacle are measured on their footprint
polygon. Distances are 0 inside a footprint.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely

from emulator.world import MIN_TARGET_DISC_M, Obstacle, Target

__all__ = [
    "Footprint",
    "heading_delta_deg",
    "point_segment_distance",
    "segment_bearing_deg",
]

# Segment-edge pairs handled per numpy block when measuring against a polygon.
_PAIR_BLOCK = 1 << 18


def heading_delta_deg(a_deg: float | np.ndarray, b_deg: float | np.ndarray) -> np.ndarray:
    """Smallest angle between two headings: |((a - b + 180) mod 360) - 180|."""
    return np.abs(np.mod(np.asarray(a_deg) - np.asarray(b_deg) + 180.0, 360.0) - 180.0)


def segment_bearing_deg(dx: np.ndarray, dy: np.ndarray) -> np.ndarray:
    """Compass bearing atan2(dx, dy) in [0, 360) of displacements (east dx, north dy)."""
    return np.mod(np.degrees(np.arctan2(dx, dy)), 360.0)


def point_segment_distance(a: np.ndarray, b: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Distance from point q (k,) to each segment a[i] -> b[i] (m, k), any dimension k."""
    d = b - a
    w = q - a
    dd = np.einsum("ij,ij->i", d, d)
    t = np.einsum("ij,ij->i", w, d)
    np.divide(t, dd, out=t, where=dd > 0.0)
    t[dd <= 0.0] = 0.0
    np.clip(t, 0.0, 1.0, out=t)
    closest = a + t[:, None] * d
    return np.linalg.norm(closest - q, axis=1)


def _cross(ax: np.ndarray, ay: np.ndarray, bx: np.ndarray, by: np.ndarray) -> np.ndarray:
    return ax * by - ay * bx


def _pairwise_point_segment(px: np.ndarray, py: np.ndarray, ax: np.ndarray, ay: np.ndarray,
                            bx: np.ndarray, by: np.ndarray) -> np.ndarray:
    """Distances of points (broadcast) to segments (broadcast)."""
    dx, dy = bx - ax, by - ay
    dd = dx * dx + dy * dy
    t = ((px - ax) * dx + (py - ay) * dy) / np.where(dd > 0.0, dd, 1.0)
    t = np.clip(np.where(dd > 0.0, t, 0.0), 0.0, 1.0)
    return np.hypot(px - (ax + t * dx), py - (ay + t * dy))


@dataclass(frozen=True, slots=True)
class Footprint:
    """A 2D shape to measure against: an exact disc, or a polygon with its edges."""

    center_xy: tuple[float, float]
    bound_radius_m: float
    disc_radius_m: float | None
    polygon: shapely.Polygon | None
    edges: np.ndarray | None

    @classmethod
    def of_target(cls, target: Target) -> Footprint:
        if target.kind != "polygon":
            radius = max(target.radius_m, MIN_TARGET_DISC_M)
            center = (target.position_m[0], target.position_m[1])
            return cls(center, radius, radius, None, None)
        return cls.of_polygon(target.geometry)

    @classmethod
    def of_obstacle(cls, obstacle: Obstacle) -> Footprint:
        return cls.of_polygon(obstacle.footprint)

    @classmethod
    def of_polygon(cls, polygon: shapely.Polygon) -> Footprint:
        x0, y0, x1, y1 = polygon.bounds
        cx, cy = (x0 + x1) / 2.0, (y0 + y1) / 2.0
        rings = [np.asarray(r.coords)[:, :2] for r in (polygon.exterior, *polygon.interiors)]
        edges = np.concatenate([np.hstack((c[:-1], c[1:])) for c in rings])
        bound = float(np.max(np.hypot(edges[:, 0] - cx, edges[:, 1] - cy)))
        shapely.prepare(polygon)
        return cls((cx, cy), bound, None, polygon, edges)

    def point_distance(self, xy: np.ndarray) -> np.ndarray:
        """Distance of each point (n, 2) to the footprint."""
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        if self.disc_radius_m is not None:
            centre = np.hypot(xy[:, 0] - self.center_xy[0], xy[:, 1] - self.center_xy[1])
            return np.maximum(centre - self.disc_radius_m, 0.0)
        return self.segment_distance(xy, xy)

    def segment_distance(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Distance of each segment a[i] -> b[i] (m, 2) to the footprint."""
        a = np.asarray(a, dtype=float).reshape(-1, 2)
        b = np.asarray(b, dtype=float).reshape(-1, 2)
        if self.disc_radius_m is not None:
            centre = point_segment_distance(a, b, np.array(self.center_xy))
            return np.maximum(centre - self.disc_radius_m, 0.0)
        out = np.empty(a.shape[0])
        assert self.edges is not None and self.polygon is not None
        step = max(1, _PAIR_BLOCK // self.edges.shape[0])
        for start in range(0, a.shape[0], step):
            stop = min(start + step, a.shape[0])
            out[start:stop] = self._polygon_block(a[start:stop], b[start:stop])
        return out

    def _polygon_block(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        assert self.edges is not None and self.polygon is not None
        inside = (shapely.intersects_xy(self.polygon, a[:, 0], a[:, 1])
                  | shapely.intersects_xy(self.polygon, b[:, 0], b[:, 1]))
        ax, ay, bx, by = (v[:, None] for v in (a[:, 0], a[:, 1], b[:, 0], b[:, 1]))
        cx, cy, dx, dy = (self.edges[None, :, k] for k in range(4))
        s1 = _cross(bx - ax, by - ay, cx - ax, cy - ay)
        s2 = _cross(bx - ax, by - ay, dx - ax, dy - ay)
        s3 = _cross(dx - cx, dy - cy, ax - cx, ay - cy)
        s4 = _cross(dx - cx, dy - cy, bx - cx, by - cy)
        collinear = (s1 == 0.0) & (s2 == 0.0)
        crossing = ((s1 * s2 <= 0.0) & (s3 * s4 <= 0.0) & ~collinear).any(axis=1)
        dist = np.minimum(
            np.minimum(_pairwise_point_segment(ax, ay, cx, cy, dx, dy),
                       _pairwise_point_segment(bx, by, cx, cy, dx, dy)),
            np.minimum(_pairwise_point_segment(cx, cy, ax, ay, bx, by),
                       _pairwise_point_segment(dx, dy, ax, ay, bx, by)),
        ).min(axis=1)
        dist[inside | crossing] = 0.0
        return dist

    def lower_bound(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """A cheap lower bound of segment_distance: distance to the bounding circle."""
        centre = point_segment_distance(a, b, np.array(self.center_xy))
        return centre - self.bound_radius_m

    def distance_xy(self, x_m: float, y_m: float) -> float:
        """Distance of one point to the footprint."""
        value = float(self.point_distance(np.array([[x_m, y_m]]))[0])
        return 0.0 if math.isclose(value, 0.0, abs_tol=1e-12) else value
