"""Coverage sweeps and visiting orders for the oracle agent.

``lawnmower`` lays parallel lanes over an area target, ``split_lanes`` shares one sweep among
several drones and ``order_visits`` orders point targets into a short open tour.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

import numpy as np
import shapely

__all__ = ["lawnmower", "order_visits", "split_lanes"]

Point3 = tuple[float, float, float]
# A cut of split_lanes moves to a sweep vertex this close to it (as a share of a piece's length).
SNAP_SHARE = 0.05


def _check_area(area: object) -> None:
    if not isinstance(area, shapely.Polygon | shapely.MultiPolygon) or area.is_empty:
        raise ValueError(f"area must be a non-empty shapely Polygon or MultiPolygon, got {area!r}")
    if not area.is_valid or not area.area > 0.0:
        raise ValueError(f"area must be a valid polygon with positive area, got {area.wkt[:80]}")


def _lane_angle_rad(area: shapely.Geometry) -> float:
    """Direction of the long side of the area's minimum rotated rectangle."""
    rect = shapely.minimum_rotated_rectangle(area)
    coords = np.asarray(rect.exterior.coords)[:4] if isinstance(rect, shapely.Polygon) else None
    if coords is None:
        return 0.0
    edges = np.diff(np.vstack((coords, coords[:1])), axis=0)
    long = edges[int(np.argmax(np.hypot(edges[:, 0], edges[:, 1])))]
    # In [-pi/2, pi/2): lanes across x are measured from the area's lowest x or y.
    angle = (math.atan2(long[1], long[0]) + math.pi / 2.0) % math.pi - math.pi / 2.0
    for exact in (-math.pi / 2.0, 0.0, math.pi / 2.0):
        if abs(angle - exact) < 1e-9:
            return -math.pi / 2.0 if exact else 0.0
    return angle


def _lane_offsets(width_m: float, spacing_m: float) -> list[float]:
    """Lane positions across the area: spacing/2 + i*spacing, the last one kept inside."""
    count = max(1, math.ceil(width_m / spacing_m - 1e-9))
    last = max(width_m - spacing_m / 2.0, width_m / 2.0)
    return [min(spacing_m / 2.0 + i * spacing_m, last) for i in range(count)]


def lawnmower(area: shapely.Polygon | shapely.MultiPolygon, altitude_m: float, spacing_m: float,
              start_xy: tuple[float, float] | None = None) -> list[Point3]:
    """Boustrophedon sweep of parallel lanes spacing_m apart, two points per lane.

    Lanes run along the long side of the area's minimum rotated rectangle; lane i lies
    spacing/2 + i*spacing from the area's edge (the last one at most spacing/2 inside the far
    edge). Each lane spans the extent of the area within its strip (the points no farther than
    spacing/2 from it), so every point of the area lies within spacing/2 of the path: a drone
    whose task disc has radius r >= spacing/2 covers the whole area. The sweep starts at the
    outermost lane end nearest start_xy (the first lane's start when start_xy is None).
    """
    _check_area(area)
    if not (math.isfinite(spacing_m) and spacing_m > 0.0):
        raise ValueError(f"spacing_m must be finite and > 0, got {spacing_m}")
    if not math.isfinite(altitude_m):
        raise ValueError(f"altitude_m must be finite, got {altitude_m}")
    angle = _lane_angle_rad(area)
    cos_a, sin_a = (0.0, -1.0) if angle == -math.pi / 2.0 else (math.cos(angle), math.sin(angle))
    # Lane frame: u along the lanes, v across them.
    local = shapely.transform(area, lambda xy: xy @ np.array([[cos_a, -sin_a], [sin_a, cos_a]]))
    u_lo, v_lo, u_hi, v_hi = local.bounds
    offsets = _lane_offsets(v_hi - v_lo, spacing_m)
    cuts = [v_lo - 1.0, *((a + b) / 2.0 + v_lo for a, b in itertools.pairwise(offsets)),
            v_hi + 1.0]
    lanes: list[tuple[float, float, float]] = []
    for i, offset in enumerate(offsets):
        strip = shapely.box(u_lo - 1.0, cuts[i], u_hi + 1.0, cuts[i + 1])
        piece = shapely.intersection(local, strip)
        if piece.is_empty:
            continue
        p_lo, _, p_hi, _ = piece.bounds
        lanes.append((p_lo, p_hi, v_lo + offset))
    best: list[tuple[float, float]] = []
    best_d = math.inf
    for reverse_lanes in (False, True):
        for first_forward in (True, False):
            order = lanes[::-1] if reverse_lanes else lanes
            path: list[tuple[float, float]] = []
            for k, (a, b, v) in enumerate(order):
                forward = first_forward == (k % 2 == 0)
                path += [(a, v), (b, v)] if forward else [(b, v), (a, v)]
            x0 = path[0][0] * cos_a - path[0][1] * sin_a
            y0 = path[0][0] * sin_a + path[0][1] * cos_a
            d = 0.0 if start_xy is None else math.hypot(x0 - start_xy[0], y0 - start_xy[1])
            if d < best_d - 1e-9:
                best, best_d = path, d
    z = float(altitude_m)
    return [(u * cos_a - v * sin_a, u * sin_a + v * cos_a, z) for u, v in best]


def split_lanes(points: Sequence[Sequence[float]], n: int) -> list[list[tuple[float, ...]]]:
    """Cut a sweep polyline into n contiguous pieces of (nearly) equal path length.

    Each piece ends where the next one starts (that point is in both). A cut moves to a sweep
    vertex within SNAP_SHARE of a piece's length; otherwise it becomes a new point on the leg.
    Joining the pieces (dropping each piece's repeated first point) traces the whole sweep.
    """
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ValueError(f"n must be an integer >= 1, got {n!r}")
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[0] == 0 or pts.shape[1] not in (2, 3):
        raise ValueError(f"points must be a non-empty list of 2D or 3D points, got shape "
                         f"{pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise ValueError("points must be finite")
    as_tuple = [tuple(float(c) for c in p) for p in pts]
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    cum = np.concatenate(([0.0], np.cumsum(seg)))
    total = float(cum[-1])
    if total == 0.0:
        return [as_tuple] + [[as_tuple[-1]] for _ in range(n - 1)]
    last = len(pts) - 1
    cuts: list[tuple[int, float]] = [(0, 0.0)]
    for k in range(1, n):
        target = k * total / n
        v = int(np.argmin(np.abs(cum - target)))
        if abs(cum[v] - target) <= SNAP_SHARE * total / n and 0 < v < last:
            cuts.append((v, 0.0))
            continue
        i = min(int(np.searchsorted(cum, target, side="right")) - 1, last - 1)
        cuts.append((i, float((target - cum[i]) / seg[i])))
    cuts.append((last, 0.0))

    def at(i: int, t: float) -> tuple[float, ...]:
        if t == 0.0:
            return as_tuple[i]
        return tuple(float(c) for c in pts[i] + t * (pts[i + 1] - pts[i]))

    pieces: list[list[tuple[float, ...]]] = []
    for (i0, t0), (i1, t1) in itertools.pairwise(cuts):
        inner = as_tuple[i0 + 1:i1 + (1 if t1 > 0.0 else 0)]
        pieces.append([at(i0, t0), *inner, at(i1, t1)])
    return pieces


def order_visits(start_xy: Sequence[float], points_xy: Sequence[Sequence[float]]) -> list[int]:
    """Indices of points_xy in a short open visiting order from start_xy.

    Nearest neighbour from the start, improved by 2-opt segment reversals until none shortens
    the path. Straight-line distances; ties go to the lower index.
    """
    if len(points_xy) == 0:
        return []
    try:
        pts = np.asarray([tuple(start_xy)[:2], *(tuple(p)[:2] for p in points_xy)], dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"start_xy and points_xy must hold (x, y) numbers: {exc}") from exc
    if pts.ndim != 2 or pts.shape[1] != 2 or not np.all(np.isfinite(pts)):
        raise ValueError(f"start_xy and points_xy must be finite (x, y) points, got {pts!r}")
    dist = np.hypot(*(pts[:, None, :] - pts[None, :, :]).transpose(2, 0, 1)).tolist()
    count = len(pts)
    tour = [0]
    left = set(range(1, count))
    while left:
        here = dist[tour[-1]]
        nxt = min(left, key=lambda j: (here[j], j))
        tour.append(nxt)
        left.remove(nxt)
    improved = True
    while improved:
        improved = False
        for i in range(1, count - 1):
            a, b = tour[i - 1], tour[i]
            for j in range(i + 1, count):
                c = tour[j]
                d = tour[j + 1] if j + 1 < count else None
                before = dist[a][b] + (dist[c][d] if d is not None else 0.0)
                after = dist[a][c] + (dist[b][d] if d is not None else 0.0)
                if after < before - 1e-9:
                    tour[i:j + 1] = tour[i:j + 1][::-1]
                    improved = True
                    b = tour[i]
    return [k - 1 for k in tour[1:]]
