"""The world's ground truth: obstacles, targets and wind, with the geometric queries on them.

Footprints are shapely polygons in the local ENU frame (metres); discs and ellipses are regular
CURVE_SEGMENTS-gons with their vertices on the exact curve. An obstacle of height 0 blocks every
altitude; a positive height blocks only ``z <= height_m``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely

from emulator.geo import DEFAULT_ORIGIN, GeoOrigin, wrap_heading_deg
from emulator.target_motion import MotionSpec

__all__ = [
    "CALM", "CURVE_SEGMENTS", "OBSTACLE_KINDS", "RAW_STOP_BEFORE_M", "TARGET_KINDS",
    "Blockage", "Obstacle", "Target", "Wind", "World", "disc_polygon", "ellipse_polygon",
]

CURVE_SEGMENTS = 128
OBSTACLE_KINDS = ("point", "circle", "ellipse", "polygon")
TARGET_KINDS = ("fixed", "moving", "waypoint", "circle", "polygon")
# Path length kept before a raw footprint when the vehicle already stands inside the margin.
RAW_STOP_BEFORE_M = 0.05
# A radius-0 target is represented by a disc of this radius (its radius_m stays 0).
MIN_TARGET_DISC_M = 0.01
_TOUCH_M = 1e-6

Point2 = tuple[float, float]
Point3 = tuple[float, float, float]


def ellipse_polygon(center_m: Point2, semi_x_m: float, semi_y_m: float) -> shapely.Polygon:
    """Axis-aligned ellipse (x/semi_x)^2 + (y/semi_y)^2 <= 1 as a CURVE_SEGMENTS-gon."""
    if not (semi_x_m > 0.0 and semi_y_m > 0.0 and math.isfinite(semi_x_m * semi_y_m)):
        raise ValueError(f"ellipse semi-axes must be finite and > 0, got {semi_x_m}, {semi_y_m}")
    angles = np.arange(CURVE_SEGMENTS) * (2.0 * math.pi / CURVE_SEGMENTS)
    xs = center_m[0] + semi_x_m * np.cos(angles)
    return shapely.Polygon(np.column_stack((xs, center_m[1] + semi_y_m * np.sin(angles))))


def disc_polygon(center_m: Point2, radius_m: float) -> shapely.Polygon:
    """Disc of radius_m around center_m as a CURVE_SEGMENTS-gon (vertices on the circle)."""
    return ellipse_polygon(center_m, radius_m, radius_m)


def _check_polygon(geometry: object, what: str) -> None:
    if not isinstance(geometry, shapely.Polygon) or geometry.is_empty:
        raise ValueError(f"{what} must be a non-empty shapely Polygon, got {geometry!r}")
    if not geometry.is_valid or geometry.area <= 1e-9:
        raise ValueError(f"{what} must be a valid polygon with area > 1e-9 m^2")


def _xy(vertices_m: Sequence[Sequence[float]]) -> np.ndarray:
    return np.array([(float(v[0]), float(v[1])) for v in vertices_m], dtype=float)


@dataclass(frozen=True, slots=True)
class Obstacle:
    """A static obstacle: a 2D footprint extruded from the ground to height_m (0: no top)."""

    id: str
    name: str
    kind: str
    footprint: shapely.Polygon
    height_m: float
    center_m: Point2

    def __post_init__(self) -> None:
        if self.kind not in OBSTACLE_KINDS:
            raise ValueError(f"obstacle {self.id}: kind must be one of {OBSTACLE_KINDS}")
        _check_polygon(self.footprint, f"obstacle {self.id} footprint")
        if not (math.isfinite(self.height_m) and self.height_m >= 0.0):
            raise ValueError(f"obstacle {self.id}: height_m must be >= 0, got {self.height_m}")

    def blocks_altitude(self, z_m: float) -> bool:
        """True if the obstacle occupies altitude z_m (height 0 occupies every altitude)."""
        return self.height_m == 0.0 or z_m <= self.height_m

    @classmethod
    def disc(cls, id: str, name: str, center_m: Point2, radius_m: float, *,
             height_m: float = 0.0, kind: str = "circle") -> Obstacle:
        """A 'circle' (or 'point') obstacle."""
        center = (float(center_m[0]), float(center_m[1]))
        return cls(id, name, kind, disc_polygon(center, radius_m), float(height_m), center)

    @classmethod
    def ellipse(cls, id: str, name: str, center_m: Point2, width_m: float, length_m: float,
                *, height_m: float = 0.0) -> Obstacle:
        """Axis-aligned ellipse: width_m is the semi-axis along x, length_m along y."""
        center = (float(center_m[0]), float(center_m[1]))
        return cls(id, name, "ellipse", ellipse_polygon(center, width_m, length_m),
                   float(height_m), center)

    @classmethod
    def polygon(cls, id: str, name: str, vertices_m: Sequence[Sequence[float]], *,
                height_m: float = 0.0, center_m: Point2 | None = None) -> Obstacle:
        """Polygon obstacle; center_m defaults to the mean of the vertices."""
        xy = _xy(vertices_m)
        cx, cy = xy.mean(axis=0).tolist() if center_m is None else center_m
        return cls(id, name, "polygon", shapely.Polygon(xy), float(height_m),
                   (float(cx), float(cy)))


@dataclass(frozen=True, slots=True)
class Target:
    """A target. Point-type targets (fixed, moving, waypoint) and circle areas are discs."""

    id: str
    name: str
    kind: str
    geometry: shapely.Polygon
    position_m: Point3
    radius_m: float
    charge_rate_pct_s: float | None = None
    motion: MotionSpec | None = None
    """How a 'moving' target moves (emulator.target_motion); None: it stands at position_m."""

    def __post_init__(self) -> None:
        if self.motion is not None and self.kind != "moving":
            raise ValueError(f"target {self.id}: only 'moving' targets have a motion")
        if self.kind not in TARGET_KINDS:
            raise ValueError(f"target {self.id}: kind must be one of {TARGET_KINDS}")
        _check_polygon(self.geometry, f"target {self.id} geometry")
        if not (math.isfinite(self.radius_m) and self.radius_m >= 0.0):
            raise ValueError(f"target {self.id}: radius_m must be >= 0, got {self.radius_m}")
        rate = self.charge_rate_pct_s
        if self.kind == "waypoint" and not (rate is not None and math.isfinite(rate) and rate > 0):
            raise ValueError(f"target {self.id}: a charging station needs charge_rate > 0")
        if self.kind != "waypoint" and rate is not None:
            raise ValueError(f"target {self.id}: only 'waypoint' targets have a charge rate")

    @property
    def is_area(self) -> bool:
        return self.kind in ("circle", "polygon")

    @property
    def is_charging_station(self) -> bool:
        return self.kind == "waypoint"

    @property
    def is_moving(self) -> bool:
        return self.kind == "moving"

    @classmethod
    def disc(cls, id: str, name: str, kind: str, position_m: Sequence[float], radius_m: float,
             *, charge_rate_pct_s: float | None = None,
             motion: MotionSpec | None = None) -> Target:
        """A disc target (any kind but 'polygon'); radius 0 gets a MIN_TARGET_DISC_M disc.
        A moving target's position_m and geometry are where it starts."""
        x, y, z = (float(v) for v in position_m)
        geometry = disc_polygon((x, y), max(float(radius_m), MIN_TARGET_DISC_M))
        return cls(id, name, kind, geometry, (x, y, z), float(radius_m), charge_rate_pct_s,
                   motion)

    @classmethod
    def polygon(cls, id: str, name: str, vertices_m: Sequence[Sequence[float]], *,
                position_m: Sequence[float] | None = None, radius_m: float = 1.0) -> Target:
        """Polygon area target; position_m defaults to the vertex mean at z 0."""
        xy = _xy(vertices_m)
        x, y, z = (*xy.mean(axis=0).tolist(), 0.0) if position_m is None else position_m
        return cls(id, name, "polygon", shapely.Polygon(xy), (float(x), float(y), float(z)),
                   float(radius_m))


@dataclass(frozen=True, slots=True)
class Wind:
    """Steady wind. from_direction_deg is meteorological: where it blows FROM, from north."""

    speed_m_s: float
    from_direction_deg: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.speed_m_s) and self.speed_m_s >= 0.0):
            raise ValueError(f"wind speed_m_s must be >= 0, got {self.speed_m_s}")
        if not math.isfinite(self.from_direction_deg):
            raise ValueError(f"wind direction must be finite, got {self.from_direction_deg}")
        object.__setattr__(self, "from_direction_deg", wrap_heading_deg(self.from_direction_deg))

    def velocity_enu_m_s(self) -> Point2:
        """The air's velocity over ground (east, north); it blows towards from + 180 degrees."""
        rad = math.radians(self.from_direction_deg)
        return -self.speed_m_s * math.sin(rad), -self.speed_m_s * math.cos(rad)


CALM = Wind(0.0, 0.0)


@dataclass(frozen=True, slots=True)
class Blockage:
    """Where a straight move must stop because of an obstacle."""

    obstacle: Obstacle
    fraction: float
    stop_m: Point3


def _ring_edges(polygon: shapely.Polygon) -> np.ndarray:
    """All ring edges of a polygon as an (n, 4) array of x0, y0, x1, y1."""
    rings = [np.asarray(r.coords)[:, :2] for r in (polygon.exterior, *polygon.interiors)]
    return np.concatenate([np.hstack((c[:-1], c[1:])) for c in rings])


def _buffer(obstacle: Obstacle, margin_m: float) -> shapely.Polygon:
    if margin_m == 0.0:
        return obstacle.footprint
    if obstacle.kind == "polygon":
        return shapely.buffer(obstacle.footprint, margin_m, quad_segs=16)
    # Curves: mitre joins offset every edge by exactly margin_m and keep the vertex count.
    return shapely.buffer(obstacle.footprint, margin_m, join_style="mitre", mitre_limit=2.0)


class World:
    """Obstacles, targets and wind of one session, with collision and containment queries."""

    def __init__(self, *, obstacles: Sequence[Obstacle] = (), targets: Sequence[Target] = (),
                 wind: Wind = CALM, origin: GeoOrigin = DEFAULT_ORIGIN,
                 safety_margin_m: float = 2.0) -> None:
        if not (math.isfinite(safety_margin_m) and safety_margin_m >= 0.0):
            raise ValueError(f"safety_margin_m must be >= 0, got {safety_margin_m}")
        self._obstacles, self._targets = tuple(obstacles), tuple(targets)
        self._wind, self._origin, self._margin_m = wind, origin, float(safety_margin_m)
        self._obstacle_by_id = {o.id: o for o in self._obstacles}
        self._target_by_id = {t.id: t for t in self._targets}
        for kind, table, items in (("obstacle", self._obstacle_by_id, self._obstacles),
                                   ("target", self._target_by_id, self._targets)):
            if len(table) != len(items):
                raise ValueError(f"{kind} ids must be unique")
        self._stations = tuple(t for t in self._targets if t.is_charging_station)
        self._build_obstacle_index()

    def _build_obstacle_index(self) -> None:
        heights = np.array([o.height_m for o in self._obstacles], dtype=float)
        self._zlim_raw = np.where(heights == 0.0, np.inf, heights)
        self._zlim_raw_list: list[float] = self._zlim_raw.tolist()
        self._zlim_buf = self._zlim_raw + self._margin_m
        self._zlim_buf_list: list[float] = self._zlim_buf.tolist()
        self._raw = np.array([o.footprint for o in self._obstacles], dtype=object)
        self._buffered = np.array([_buffer(o, self._margin_m) for o in self._obstacles],
                                  dtype=object)
        shapely.prepare(np.concatenate((self._raw, self._buffered)))
        self._raw_edges = [_ring_edges(p) for p in self._raw]
        self._buf_edges = [_ring_edges(p) for p in self._buffered]
        bounds = shapely.bounds(self._buffered).reshape(-1, 4)
        self._circle_x, self._circle_y = (bounds[:, :2] + bounds[:, 2:]).T / 2.0
        self._circle_r2 = np.array([
            np.max(np.hypot(e[:, 0] - cx, e[:, 1] - cy)) + _TOUCH_M
            for e, cx, cy in zip(self._buf_edges, self._circle_x, self._circle_y, strict=True)
        ]) ** 2
        self._raw_tree = shapely.STRtree(self._raw)

    @property
    def obstacles(self) -> tuple[Obstacle, ...]:
        return self._obstacles

    @property
    def targets(self) -> tuple[Target, ...]:
        return self._targets

    @property
    def wind(self) -> Wind:
        return self._wind

    @property
    def origin(self) -> GeoOrigin:
        return self._origin

    @property
    def safety_margin_m(self) -> float:
        return self._margin_m

    def obstacle(self, id: str) -> Obstacle:
        if id not in self._obstacle_by_id:
            raise KeyError(f"no obstacle with id {id!r} in this world")
        return self._obstacle_by_id[id]

    def target(self, id: str) -> Target:
        if id not in self._target_by_id:
            raise KeyError(f"no target with id {id!r} in this world")
        return self._target_by_id[id]

    def inside_obstacles(self, x_m: np.ndarray, y_m: np.ndarray, z_m: np.ndarray) -> np.ndarray:
        """Mask of points inside or on a raw footprint at an altitude the obstacle occupies."""
        x, y, z = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x_m, y_m, z_m)))
        inside = np.zeros(x.shape, dtype=bool)
        if not self._obstacles or x.size == 0:
            return inside
        # One tree query gives (point, obstacle) pairs whose 2D footprint holds the point.
        point, obstacle = self._raw_tree.query(shapely.points(x.ravel(), y.ravel()),
                                               predicate="intersects")
        inside.reshape(-1)[point[z.ravel()[point] <= self._zlim_raw[obstacle]]] = True
        return inside

    def clearance_ok(self, x_m: float, y_m: float, z_m: float) -> bool:
        """True if the point is not inside any obstacle (raw footprints, heights respected)."""
        return not self.inside_obstacles(np.array([x_m]), np.array([y_m]), np.array([z_m]))[0]

    def charging_station_at(self, x_m: float, y_m: float) -> Target | None:
        """The charging station whose disc contains (x_m, y_m), the nearest centre first."""
        best: Target | None = None
        best_d = math.inf
        for station in self._stations:
            d = math.hypot(x_m - station.position_m[0], y_m - station.position_m[1])
            if d <= station.radius_m + 1e-9 and d < best_d:
                best, best_d = station, d
        return best

    def first_blockage(self, start_m: Sequence[float], end_m: Sequence[float]) -> Blockage | None:
        """Earliest point of the straight move start -> end where collision prevention stops.

        Blocked: 2D inside a footprint buffered by safety_margin_m and z <= height + margin
        (any z for height 0). An obstacle whose buffered zone already holds the start is judged
        on its raw volume instead, stopping RAW_STOP_BEFORE_M of path before it; a start
        strictly inside a raw volume may leave it. Grazing contacts do not block.
        """
        x0, y0, z0 = (float(v) for v in start_m)
        x1, y1, z1 = (float(v) for v in end_m)
        dx, dy, dz = x1 - x0, y1 - y0, z1 - z0
        length_m = math.sqrt(dx * dx + dy * dy + dz * dz)
        if not self._obstacles:
            return None
        if length_m == 0.0:
            hits = np.flatnonzero(shapely.intersects_xy(self._raw, x0, y0)
                                  & (z0 <= self._zlim_raw))
            return Blockage(self._obstacles[hits[0]], 0.0, (x0, y0, z0)) if hits.size else None
        cand = self._candidates(x0, y0, dx, dy)
        cand = cand[self._zlim_buf[cand] >= min(z0, z1)]  # others are below the whole move
        if cand.size == 0:
            return None
        planar_m = math.hypot(dx, dy)
        tol = _TOUCH_M / planar_m if planar_m > 0.0 else _TOUCH_M
        zlim_buf, zlim_raw = self._zlim_buf_list, self._zlim_raw_list
        pieces = _pieces(cand, self._buf_edges, self._buffered, x0, y0, dx, dy)
        zone = sorted({o for o, a, b in pieces
                       if a <= tol and b >= -tol and z0 <= zlim_buf[o] + 1e-9})
        modes = [(o, a, b, False) for o, a, b in pieces if o not in zone]
        if zone:
            raw = _pieces(np.array(zone), self._raw_edges, self._raw, x0, y0, dx, dy)
            modes += [(o, a, b, True) for o, a, b in raw]
        best_t, best_o = math.inf, -1
        for o, a, b, is_raw in modes:
            zlim = zlim_raw[o] if is_raw else zlim_buf[o]
            lo, hi = _altitude_interval(zlim, z0, dz)
            entry = max(a, lo, 0.0)
            if (min(b, hi, 1.0) - entry) * length_m <= 1e-9:
                continue
            if is_raw:
                if entry <= tol and a < -tol and b > tol and z0 < zlim - 1e-9:
                    continue  # already inside this raw volume: it may leave
                entry = max(entry - RAW_STOP_BEFORE_M / length_m, 0.0)
            if entry < best_t or (entry == best_t and o < best_o):
                best_t, best_o = entry, o
        if best_o < 0:
            return None
        t = best_t
        return Blockage(self._obstacles[best_o], t, (x0 + t * dx, y0 + t * dy, z0 + t * dz))

    def _candidates(self, x0: float, y0: float, dx: float, dy: float) -> np.ndarray:
        """Obstacles whose buffered bounding circle meets the 2D segment."""
        cx, cy = self._circle_x - x0, self._circle_y - y0
        if (d2 := dx * dx + dy * dy) > 0.0:
            t = cx * (dx / d2) + cy * (dy / d2)
            np.minimum(np.maximum(t, 0.0, out=t), 1.0, out=t)
            cx -= t * dx
            cy -= t * dy
        return np.flatnonzero(cx * cx + cy * cy <= self._circle_r2)


def _pieces(ids: np.ndarray, edges: list[np.ndarray], polygons: np.ndarray,
            x0: float, y0: float, dx: float, dy: float) -> list[tuple[int, float, float]]:
    """Inside intervals (owner, t_in, t_out) of the segment's infinite line, t in fractions.

    The line is perturbed to the right of its direction (a vertex on the line counts as left of
    it), so vertex hits and collinear edges give consistent crossings that pair up per polygon.
    """
    d2 = dx * dx + dy * dy
    if d2 == 0.0:
        inside = ids[shapely.intersects_xy(polygons[ids], x0, y0)]
        return [(int(o), -math.inf, math.inf) for o in inside]
    e = np.concatenate([edges[i] for i in ids]) - (x0, y0, x0, y0)
    # Elementwise (not BLAS) so a vertex shared by two edges gets the very same side value.
    side_a = dx * e[:, 1] - dy * e[:, 0]
    side_b = dx * e[:, 3] - dy * e[:, 2]
    mask = (side_a >= 0.0) != (side_b >= 0.0)
    if not mask.any():
        return []
    owners = np.repeat(ids, [len(edges[i]) for i in ids])[mask]
    c, sa, sb = e[mask], side_a[mask], side_b[mask]
    u = sa / (sa - sb)
    along_a = dx * c[:, 0] + dy * c[:, 1]
    t = (along_a + u * (dx * c[:, 2] + dy * c[:, 3] - along_a)) / d2
    order = np.lexsort((t, owners))
    ts: list[float] = t[order].tolist()
    os_: list[int] = owners[order].tolist()
    return list(zip(os_[0::2], ts[0::2], ts[1::2], strict=True))


def _altitude_interval(zlim: float, z0: float, dz: float) -> tuple[float, float]:
    """Fractions [lo, hi] of the segment where z0 + t*dz <= zlim (empty when lo > hi)."""
    if zlim == math.inf:
        return -math.inf, math.inf
    if dz == 0.0:
        return (-math.inf, math.inf) if z0 <= zlim else (math.inf, -math.inf)
    tz = (zlim - z0) / dz
    return (-math.inf, tz) if dz > 0.0 else (tz, math.inf)
