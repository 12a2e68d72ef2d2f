"""Footprints of generated entities and the layout that places them with clearances.

A :class:`ShapeTemplate` is a footprint shape around its own centre; :meth:`ShapeTemplate.at`
puts it at a point, rounding every coordinate to 0.1 m, and the resulting :class:`Footprint`
builds the exact geometry the emulator will build from the rounded numbers (discs and ellipses
as :data:`emulator.world.CURVE_SEGMENTS`-gons). :class:`Layout` keeps the placed footprints and
accepts a new one only if it lies inside the map with :data:`MAP_MARGIN_M` and keeps the
clearance of :func:`clearance_m` from every footprint already placed.
"""

from __future__ import annotations

import itertools
import math
import random
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import shapely

from emulator.world import disc_polygon, ellipse_polygon

__all__ = [
    "CLEARANCE_SLACK_M",
    "GROUPS",
    "MAP_MARGIN_M",
    "SHRINK_STEPS",
    "TRIES_PER_SIZE",
    "Footprint",
    "Layout",
    "PlacementError",
    "ShapeTemplate",
    "clearance_m",
    "convex_offsets",
    "rectangle_offsets",
]

Point2 = tuple[float, float]

GROUPS: tuple[str, ...] = ("drone", "target", "obstacle")
# Minimum distance between footprints of two groups (metres).
_CLEARANCE_TABLE_M = np.array([
    #  drone  target obstacle
    [8.0, 10.0, 20.0],   # drone
    [10.0, 10.0, 15.0],  # target
    [20.0, 15.0, 25.0],  # obstacle
])
# Every footprint (targets, obstacles, drones) stays this far inside the map's edges.
MAP_MARGIN_M = 20.0
# Extra distance kept so the clearances also hold for the exact curves, not only their polygons.
CLEARANCE_SLACK_M = 0.1
# Random positions tried for one size before the size is reduced.
TRIES_PER_SIZE = 120
# Successive size factors: 1 keeps the drawn size, 0 falls back to the smallest size allowed.
SHRINK_STEPS: tuple[float, ...] = (1.0, 0.6, 0.3, 0.0)


class PlacementError(RuntimeError):
    """Raised when an entity cannot be placed even at its smallest size."""


def clearance_m(group_a: str, group_b: str) -> float:
    """The minimum distance between the footprints of two groups (drone, target, obstacle)."""
    return float(_CLEARANCE_TABLE_M[_group_code(group_a), _group_code(group_b)])


def _group_code(group: str) -> int:
    if group not in GROUPS:
        raise ValueError(f"group must be one of {', '.join(GROUPS)}; got {group!r}")
    return GROUPS.index(group)


def rectangle_offsets(half_length_m: float, half_width_m: float,
                      rotation_deg: float) -> tuple[Point2, ...]:
    """Corners of a rectangle around (0, 0), counter-clockwise, rotated by rotation_deg."""
    corners = ((-half_length_m, -half_width_m), (half_length_m, -half_width_m),
               (half_length_m, half_width_m), (-half_length_m, half_width_m))
    return _rotated(corners, rotation_deg)


def convex_offsets(semi_a_m: float, semi_b_m: float, angles_rad: Sequence[float],
                   rotation_deg: float) -> tuple[Point2, ...]:
    """Vertices on the ellipse with semi-axes (a, b) at increasing angles: a convex polygon
    around (0, 0), rotated by rotation_deg."""
    if len(angles_rad) < 3 or any(b <= a for a, b in itertools.pairwise(angles_rad)) \
            or angles_rad[-1] - angles_rad[0] >= 2.0 * math.pi:
        raise ValueError(f"angles_rad must be >= 3 increasing angles spanning less than a "
                         f"turn, got {list(angles_rad)}")
    points = [(semi_a_m * math.cos(t), semi_b_m * math.sin(t)) for t in angles_rad]
    return _rotated(points, rotation_deg)


def _rotated(points: Sequence[Point2], rotation_deg: float) -> tuple[Point2, ...]:
    c, s = math.cos(math.radians(rotation_deg)), math.sin(math.radians(rotation_deg))
    return tuple((c * x - s * y, s * x + c * y) for x, y in points)


@dataclass(frozen=True, slots=True)
class Footprint:
    """A placed footprint; shape is 'point' (a drone), 'disc', 'ellipse' or 'polygon'.

    Ellipse semi-axes are along x and y; vertices are absolute; reach_m is the radius of a
    disc around center_m holding the whole footprint (exact for points and discs); bounds_m is
    (min x, min y, max x, max y).
    """

    shape: str
    center_m: Point2
    radius_m: float = 0.0
    semi_axes_m: Point2 = (0.0, 0.0)
    vertices_m: tuple[Point2, ...] = ()

    @property
    def is_round(self) -> bool:
        """True for points and discs, whose distances follow from centre and radius alone."""
        return self.shape in ("point", "disc")

    @property
    def reach_m(self) -> float:
        if self.shape == "polygon":
            cx, cy = self.center_m
            return max(math.hypot(x - cx, y - cy) for x, y in self.vertices_m)
        return max(self.radius_m, *self.semi_axes_m)

    @property
    def inner_m(self) -> float:
        """A radius around the centre whose disc lies inside the footprint (0 if none)."""
        if self.shape == "point":
            return 0.0
        if self.shape != "polygon":
            # The CURVE_SEGMENTS-gon of a disc or ellipse holds a disc a little smaller than
            # its smallest semi-axis; 1 % is far more than the chord sag of 128 segments.
            return 0.99 * (self.radius_m if self.shape == "disc" else min(self.semi_axes_m))
        cx, cy = self.center_m
        ring = [(x - cx, y - cy) for x, y in self.vertices_m]
        edges = list(zip(ring, ring[1:] + ring[:1], strict=True))
        twice_area = sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in edges)
        sign = 1.0 if twice_area > 0.0 else -1.0
        inner = math.inf
        for (x0, y0), (x1, y1) in edges:
            length = math.hypot(x1 - x0, y1 - y0)
            if length == 0.0:
                return 0.0
            # Signed distance of the centre (the origin here) to the edge's line, inside > 0.
            inner = min(inner, sign * (x0 * y1 - x1 * y0) / length)
        return max(inner, 0.0)

    @property
    def bounds_m(self) -> tuple[float, float, float, float]:
        if self.shape == "polygon":
            xs, ys = [v[0] for v in self.vertices_m], [v[1] for v in self.vertices_m]
            return min(xs), min(ys), max(xs), max(ys)
        (cx, cy), r = self.center_m, self.radius_m
        sx, sy = self.semi_axes_m if self.shape == "ellipse" else (r, r)
        return cx - sx, cy - sy, cx + sx, cy + sy

    def geometry(self) -> shapely.Geometry:
        """The footprint as the emulator builds it (discs and ellipses as polygons with their
        vertices on the curve; a point as a shapely Point)."""
        if self.shape == "point":
            return shapely.Point(*self.center_m)
        if self.shape == "disc":
            return disc_polygon(self.center_m, self.radius_m)
        if self.shape == "ellipse":
            return ellipse_polygon(self.center_m, *self.semi_axes_m)
        return shapely.Polygon(self.vertices_m)


@dataclass(frozen=True, slots=True)
class ShapeTemplate:
    """A footprint shape around (0, 0) that is not placed yet."""

    shape: str
    radius_m: float = 0.0
    semi_axes_m: Point2 = (0.0, 0.0)
    offsets_m: tuple[Point2, ...] = ()

    @classmethod
    def point(cls) -> ShapeTemplate:
        return cls("point")

    @classmethod
    def disc(cls, radius_m: float) -> ShapeTemplate:
        """A disc; the radius is rounded to 0.1 m."""
        return cls("disc", radius_m=round(radius_m, 1))

    @classmethod
    def ellipse(cls, semi_x_m: float, semi_y_m: float) -> ShapeTemplate:
        """An axis-aligned ellipse; the semi-axes are rounded to 0.1 m."""
        return cls("ellipse", semi_axes_m=(round(semi_x_m, 1), round(semi_y_m, 1)))

    @classmethod
    def polygon(cls, offsets_m: Sequence[Point2]) -> ShapeTemplate:
        """A polygon given by its vertices relative to its centre."""
        if len(offsets_m) < 3:
            raise ValueError(f"a polygon needs at least 3 vertices, got {len(offsets_m)}")
        return cls("polygon", offsets_m=tuple((float(x), float(y)) for x, y in offsets_m))

    @property
    def reach_m(self) -> float:
        """The largest distance from the centre to the shape."""
        if self.shape == "polygon":
            return max(math.hypot(x, y) for x, y in self.offsets_m)
        return max(self.radius_m, *self.semi_axes_m)

    def at(self, x_m: float, y_m: float) -> Footprint:
        """The shape centred at (x_m, y_m), every coordinate rounded to 0.1 m."""
        cx, cy = round(x_m, 1), round(y_m, 1)
        if self.shape != "polygon":
            return Footprint(self.shape, (cx, cy), self.radius_m, self.semi_axes_m)
        vertices = tuple((round(cx + dx, 1), round(cy + dy, 1)) for dx, dy in self.offsets_m)
        mx = round(sum(v[0] for v in vertices) / len(vertices), 1)
        my = round(sum(v[1] for v in vertices) / len(vertices), 1)
        return Footprint("polygon", (mx, my), vertices_m=vertices)


class Layout:
    """The footprints placed so far on a width x height map, with their groups."""

    def __init__(self, width_m: float, height_m: float, *,
                 margin_m: float = MAP_MARGIN_M) -> None:
        if not (width_m > 2.0 * margin_m and height_m > 2.0 * margin_m):
            raise ValueError(f"map {width_m} x {height_m} m is too small for a "
                             f"{margin_m} m margin")
        self.width_m, self.height_m, self.margin_m = float(width_m), float(height_m), margin_m
        self._footprints: list[Footprint] = []
        self._geometries: list[shapely.Geometry] = []
        # Per footprint: centre x, centre y, reach, inner radius, group code, is_round.
        self._cx, self._cy = np.empty(0), np.empty(0)
        self._reach, self._inner = np.empty(0), np.empty(0)
        self._codes = np.empty(0, dtype=int)
        self._round = np.empty(0, dtype=bool)

    @property
    def footprints(self) -> tuple[Footprint, ...]:
        return tuple(self._footprints)

    def inside_map(self, footprint: Footprint) -> bool:
        """True if the footprint lies inside the map with the margin."""
        x0, y0, x1, y1 = footprint.bounds_m
        m = self.margin_m
        return x0 >= m and y0 >= m and x1 <= self.width_m - m and y1 <= self.height_m - m

    def fits(self, group: str, footprint: Footprint) -> bool:
        """True if the footprint is a valid shape inside the map and keeps the clearance of
        its group from every footprint placed so far."""
        code = _group_code(group)
        if not self.inside_map(footprint):
            return False
        geometry: shapely.Geometry | None = None
        if self._footprints:
            need = _CLEARANCE_TABLE_M[code, self._codes] + CLEARANCE_SLACK_M
            centres = np.hypot(self._cx - footprint.center_m[0],
                               self._cy - footprint.center_m[1])
            gap = centres - (self._reach + footprint.reach_m)
            near = np.flatnonzero(gap < need)
            # Discs inside both footprints that are already too close: certainly a clash.
            if near.size and np.any(centres[near] - (self._inner[near] + footprint.inner_m)
                                    < need[near]):
                return False
            if near.size and footprint.is_round:
                exact = near[self._round[near]]
                if np.any(gap[exact] < need[exact]):
                    return False
                near = near[~self._round[near]]
            if near.size:
                geometry = footprint.geometry()
                others = [self._geometries[k] for k in near]
                if not np.all(shapely.distance(geometry, others) >= need[near]):
                    return False
        if footprint.shape == "polygon":
            geometry = footprint.geometry() if geometry is None else geometry
            return bool(geometry.is_valid)
        return True

    def add(self, group: str, footprint: Footprint) -> None:
        """Record a footprint without checking it."""
        geometry = footprint.geometry()
        self._footprints.append(footprint)
        self._geometries.append(geometry)
        self._cx = np.append(self._cx, footprint.center_m[0])
        self._cy = np.append(self._cy, footprint.center_m[1])
        self._reach = np.append(self._reach, footprint.reach_m)
        self._inner = np.append(self._inner, footprint.inner_m)
        self._codes = np.append(self._codes, _group_code(group))
        self._round = np.append(self._round, footprint.is_round)

    def place(self, rng: random.Random, group: str,
              template_for: Callable[[float], ShapeTemplate], *, label: str,
              within: tuple[Point2, float] | None = None) -> Footprint:
        """Place a footprint of the group by rejection sampling and record it.

        template_for(shrink) draws a shape; shrink runs through SHRINK_STEPS, and each shape
        gets TRIES_PER_SIZE uniform positions (inside the disc ``within`` = (centre, radius)
        when given, else anywhere on the map). Raises PlacementError naming the label.
        """
        for shrink in SHRINK_STEPS:
            template = template_for(shrink)
            for _ in range(TRIES_PER_SIZE):
                position = self._sample(rng, template.reach_m, within)
                if position is None:
                    break
                footprint = template.at(*position)
                if self.fits(group, footprint):
                    self.add(group, footprint)
                    return footprint
        raise PlacementError(
            f"cannot place {label} on the {self.width_m:g} x {self.height_m:g} m map: "
            f"no free position after {len(SHRINK_STEPS)} sizes x {TRIES_PER_SIZE} tries")

    def _sample(self, rng: random.Random, reach_m: float,
                within: tuple[Point2, float] | None) -> Point2 | None:
        low = self.margin_m + reach_m + CLEARANCE_SLACK_M
        high_x, high_y = self.width_m - low, self.height_m - low
        if high_x < low or high_y < low:
            return None
        if within is None:
            return rng.uniform(low, high_x), rng.uniform(low, high_y)
        (bx, by), radius = within
        r, angle = radius * math.sqrt(rng.random()), rng.uniform(0.0, 2.0 * math.pi)
        return bx + r * math.cos(angle), by + r * math.sin(angle)
