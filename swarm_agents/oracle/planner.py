"""Obstacle-avoiding path planning for the oracle agent, exact against collision prevention.

The planner rasterises the obstacles that block the flight altitude, inflated by a planning
clearance, onto a grid, finds a shortest grid path with Dijkstra and string-pulls it into a few
straight legs. Every leg it returns passes ``World.first_blockage`` (the autopilot's own test) and,
away from the start and goal, keeps a soft clearance from the raw footprints so that small
tracking errors do not trip collision prevention.
"""

from __future__ import annotations

import functools
import math
import struct
from collections import OrderedDict
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypeVar

import numpy as np
import shapely

from emulator.world import World

if TYPE_CHECKING:
    import scipy.sparse

__all__ = ["NoPath", "PathPlanner"]

K = TypeVar("K")
V = TypeVar("V")
Point2 = tuple[float, float]
Point3 = tuple[float, float, float]

# Obstacles whose top is this close below the flight altitude still count as blocking it.
VERTICAL_SLACK_M = 1.0
# Extra grid border (in cells) beyond the inflated obstacles, so detours can pass outside them.
BORDER_CELLS = 4
# The largest grid the planner builds; a larger map needs a coarser cell_m.
MAX_GRID_CELLS = 4_000_000
# Routing grids kept built: a grid is about 100 bytes per free cell (an extreme-level world's
# 100,000 cells: 10 MB), and a session's flights route in one altitude band for stretches of
# many routes, so only the last band's grid is kept; another is built (a few tens of ms) when
# a route needs it: an extreme-level session builds 18-23 grids in 20 tasks (0.3-0.5 s).
GRIDS_KEPT = 1
# Attachment of start/goal to the grid: clear legs wanted, and the most legs tried.
_ATTACH_WANTED = 6
# Dijkstra first searches only paths up to this detour over the straight distance.
DETOUR_FACTOR = 1.5
DETOUR_EXTRA_CELLS = 25
_ATTACH_MAX_TRIES = 96
_QUAD_SEGS = 8
_EPS_M = 1e-6
# Routes remembered by (start, goal): a route is a function of the world and its ends, and
# an oracle asks some again (a tracking session: about one in ten).
ROUTES_KEPT = 256
# Grid searches kept by (band, sources): 12 bytes per grid node each (1.2 MB for an
# extreme-level world); a meeting's goals are all tried from one spot, one after another.
SEARCHES_KEPT = 1


class NoPath(Exception):
    """Raised when no obstacle-free path exists between two points."""


@dataclass(frozen=True, slots=True)
class _Band:
    """The obstacles that block one altitude band: their footprints and clearance index."""

    ids: tuple[int, ...]
    footprints: np.ndarray  # raw footprints of ids (object array)
    tree: shapely.STRtree | None


@dataclass(frozen=True, slots=True)
class _Search:
    """A grid search from a set of sources: every node within limit_m settled."""

    limit_m: float
    dist: np.ndarray  # (n,) float64, inf where not settled
    pred: np.ndarray  # (n,) int32, negative at sources and where not settled


@dataclass(frozen=True, slots=True)
class _Grid:
    """The routing grid of one band: free cells numbered as graph nodes, and the graph."""

    x0_m: float
    y0_m: float
    nx: int
    ny: int
    node: np.ndarray  # (ny, nx) int32, -1 where blocked
    cell_of_node: np.ndarray  # (n,) int32 flat cell index
    graph: scipy.sparse.csr_matrix

    def centre(self, flat: int, cell_m: float) -> Point2:
        iy, ix = divmod(int(flat), self.nx)
        return self.x0_m + (ix + 0.5) * cell_m, self.y0_m + (iy + 0.5) * cell_m


def _point3(value: Sequence[float], name: str) -> Point3:
    try:
        x, y, z = (float(v) for v in value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be three numbers (x, y, z), got {value!r}") from exc
    if not all(math.isfinite(v) for v in (x, y, z)):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return x, y, z


class PathPlanner:
    """Plans obstacle-free polylines through one world. The obstacles of each altitude band are
    indexed once; a band's routing grid is built when a route needs it, and only the
    GRIDS_KEPT grids used last are kept."""

    def __init__(self, world: World, *, clearance_m: float = 6.0, cell_m: float = 4.0) -> None:
        if not (math.isfinite(cell_m) and cell_m > 0.0):
            raise ValueError(f"cell_m must be finite and > 0, got {cell_m}")
        if not math.isfinite(clearance_m):
            raise ValueError(f"clearance_m must be finite, got {clearance_m}")
        # A grid edge between two free cell centres keeps this far from every raw footprint.
        self._soft_m = clearance_m - cell_m * math.sqrt(0.5) - 0.1
        margin_m = world.safety_margin_m
        if self._soft_m <= margin_m * 1.001 + 0.05:
            least = margin_m * 1.001 + 0.15 + cell_m * math.sqrt(0.5)
            raise ValueError(
                f"clearance_m must exceed {least:.3f} (safety margin {margin_m} m plus half a "
                f"cell diagonal for cell_m {cell_m}), got {clearance_m}")
        self.world = world
        self.clearance_m = float(clearance_m)
        self.cell_m = float(cell_m)
        heights = np.array([o.height_m for o in world.obstacles], dtype=float)
        self._top_m = np.where(heights == 0.0, np.inf, heights + margin_m)
        self._bands: dict[tuple[int, ...], _Band] = {}
        self._grids: OrderedDict[tuple[int, ...], _Grid] = OrderedDict()
        self._routes: OrderedDict[bytes, tuple[Point3, ...]] = OrderedDict()
        self._searches: OrderedDict[tuple[tuple[int, ...], tuple[int, ...]], _Search] = \
            OrderedDict()

    # ------------------------------------------------------------------ public
    def leg_clear(self, a_m: Sequence[float], b_m: Sequence[float]) -> bool:
        """True if collision prevention lets the straight move a -> b through."""
        a, b = _point3(a_m, "a_m"), _point3(b_m, "b_m")
        return self.world.first_blockage(a, b) is None

    def plan(self, start_m: Sequence[float], goal_m: Sequence[float]) -> list[Point3]:
        """Waypoints after start, ending exactly at goal, every leg clear of collision prevention.

        All waypoints are at the goal's altitude and the first leg climbs or descends; when that
        leg is blocked the altitude change is made vertically at the start instead. Only if a
        vertical change at the start is impossible (descending onto an obstacle's roof) is the
        route flown at the start's altitude with a vertical change at the goal.
        """
        start, goal = _point3(start_m, "start_m"), _point3(goal_m, "goal_m")
        key = struct.pack("6d", *start, *goal)  # every bit: -0.0 is not 0.0
        route = _remember(self._routes, key, ROUTES_KEPT,
                          lambda: tuple(self._plan(start, goal)))
        return list(route)

    def _plan(self, start: Point3, goal: Point3) -> list[Point3]:
        direct = self.world.first_blockage(start, goal) is None
        if direct and self._soft_ok(start, goal):
            return [goal]
        try:
            return self._plan_via(start, goal, goal[2])
        except NoPath as exc:
            if direct:
                return [goal]
            if abs(start[2] - goal[2]) <= _EPS_M:
                raise
            first_error = exc
        top = (goal[0], goal[1], start[2])
        if self.world.first_blockage(top, goal) is not None:
            raise first_error
        try:
            return [*self._plan_via(start, top, start[2]), goal]
        except NoPath:
            raise first_error from None

    # ------------------------------------------------------------ altitudes
    def _plan_via(self, start: Point3, goal: Point3, z_m: float) -> list[Point3]:
        """A route flown at z_m (= goal altitude) after a first leg that changes altitude."""
        level_start = (start[0], start[1], z_m)
        xy = self._plan_level(level_start, goal)
        route = [(x, y, z_m) for x, y in xy[:-1]] + [goal]
        if abs(start[2] - z_m) <= _EPS_M:
            return route
        first = route[0]
        if (self.world.first_blockage(start, first) is None
                and self._soft_ok(start, first)):
            return route
        if self.world.first_blockage(start, level_start) is None:
            return [level_start, *route]
        raise NoPath(f"cannot climb or descend from {start} to altitude {z_m} m")

    def _plan_level(self, start: Point3, goal: Point3) -> list[Point2]:
        """2D waypoints (after start, ending at goal) of a route at the goal's altitude."""
        z_m = goal[2]
        if not self.world.clearance_ok(*goal):
            raise NoPath(f"goal {goal} lies inside an obstacle")
        err: NoPath | None = None
        for slack_m in (VERTICAL_SLACK_M, 0.0):
            band = self._band(z_m, slack_m)
            try:
                return self._route_in_band(band, start, goal)
            except NoPath as exc:
                err = err or exc
            if self._band_ids(z_m, 0.0) == band.ids:
                break
        assert err is not None
        raise err

    # ---------------------------------------------------------------- bands
    def _band_ids(self, z_m: float, slack_m: float) -> tuple[int, ...]:
        return tuple(np.flatnonzero(self._top_m + slack_m >= z_m).tolist())

    def _band(self, z_m: float, slack_m: float) -> _Band:
        ids = self._band_ids(z_m, slack_m)
        band = self._bands.get(ids)
        if band is None:
            band = self._bands[ids] = self._build_band(ids)
        return band

    def _build_band(self, ids: tuple[int, ...]) -> _Band:
        footprints = np.array([self.world.obstacles[i].footprint for i in ids], dtype=object)
        if not ids:
            return _Band(ids, footprints, None)
        shapely.prepare(footprints)
        return _Band(ids, footprints, shapely.STRtree(footprints))

    @functools.cached_property
    def _inflated(self) -> tuple[np.ndarray, np.ndarray]:
        """Every obstacle's footprint grown by clearance_m (prepared), and their bounds: made
        once, a band's grid takes its own."""
        every = np.array([o.footprint for o in self.world.obstacles], dtype=object)
        inflated = shapely.buffer(every, self.clearance_m, quad_segs=_QUAD_SEGS)
        shapely.prepare(inflated)
        return inflated, shapely.bounds(inflated)

    def _grid(self, band: _Band) -> _Grid:
        """The routing grid of a band with obstacles (built again if it was dropped)."""
        return _remember(self._grids, band.ids, GRIDS_KEPT, lambda: self._build_grid(band))

    def _build_grid(self, band: _Band) -> _Grid:
        cell = self.cell_m
        every, every_bounds = self._inflated
        ids = list(band.ids)
        inflated, bounds = every[ids], every_bounds[ids]
        pad = BORDER_CELLS * cell
        x0 = math.floor((bounds[:, 0].min() - pad) / cell) * cell
        y0 = math.floor((bounds[:, 1].min() - pad) / cell) * cell
        nx = math.ceil((bounds[:, 2].max() + pad - x0) / cell)
        ny = math.ceil((bounds[:, 3].max() + pad - y0) / cell)
        if nx * ny > MAX_GRID_CELLS:
            raise ValueError(f"planning grid of {nx} x {ny} cells exceeds {MAX_GRID_CELLS}; "
                             f"use a larger cell_m than {cell}")
        free = np.ones((ny, nx), dtype=bool)
        for poly, (bx0, by0, bx1, by1) in zip(inflated, bounds, strict=True):
            ix0, iy0 = int((bx0 - x0) / cell), int((by0 - y0) / cell)
            ix1, iy1 = int((bx1 - x0) / cell) + 1, int((by1 - y0) / cell) + 1
            xs = x0 + (np.arange(ix0, ix1) + 0.5) * cell
            ys = y0 + (np.arange(iy0, iy1) + 0.5) * cell
            free[iy0:iy1, ix0:ix1] &= ~shapely.intersects_xy(poly, xs[None, :], ys[:, None])
        cell_of_node = np.flatnonzero(free.ravel()).astype(np.int32)
        node = np.full((ny, nx), -1, dtype=np.int32)
        node.ravel()[cell_of_node] = np.arange(cell_of_node.size, dtype=np.int32)
        return _Grid(x0, y0, nx, ny, node, cell_of_node, _grid_graph(node, cell_of_node, cell))

    # -------------------------------------------------------------- routing
    def _route_in_band(self, band: _Band, start: Point3, goal: Point3) -> list[Point2]:
        z_m = goal[2]
        if self.world.first_blockage(start, goal) is None and self._soft_ok(start, goal):
            return [goal[:2]]
        if not band.ids:
            raise NoPath(f"no obstacle blocks altitude {z_m} m, yet {start} -> {goal} is blocked")
        grid = self._grid(band)
        sources = self._attach(grid, start, z_m, leaving=True)
        if not sources:
            raise NoPath(f"start {start} cannot reach open space at altitude {z_m} m")
        targets = self._attach(grid, goal, z_m, leaving=False)
        if not targets:
            raise NoPath(f"goal {goal} cannot be reached from open space at altitude {z_m} m")
        gx, gy = goal[0], goal[1]
        direct_m = math.hypot(gx - start[0], gy - start[1])
        for limit_m in (DETOUR_FACTOR * direct_m + DETOUR_EXTRA_CELLS * self.cell_m, math.inf):
            dist, pred = self._search(band, grid, sources, limit_m)
            best_node, best_cost = -1, math.inf
            for n in targets:
                if not dist[n] <= limit_m:  # beyond the limit (or not reached)
                    continue
                cx, cy = grid.centre(grid.cell_of_node[n], self.cell_m)
                cost = dist[n] + math.hypot(cx - gx, cy - gy)
                if cost < best_cost:
                    best_node, best_cost = n, cost
            if best_node >= 0:
                break
        else:
            raise NoPath(f"no obstacle-free path from {start[:2]} to {goal[:2]} at altitude "
                         f"{z_m} m")
        chain = [best_node]
        while pred[chain[-1]] >= 0:
            chain.append(int(pred[chain[-1]]))
        chain.reverse()
        points = [start] + [(*grid.centre(grid.cell_of_node[n], self.cell_m), z_m)
                            for n in chain] + [goal]
        route = _string_pull(points, self._leg_ok)
        for a, b in zip([start, *route[:-1]], route, strict=True):
            if self.world.first_blockage(a, b) is not None:
                raise NoPath(f"planned leg {a} -> {b} is blocked")
        return [(p[0], p[1]) for p in route]

    def _search(self, band: _Band, grid: _Grid, sources: list[int], limit_m: float
                ) -> tuple[np.ndarray, np.ndarray]:
        """Shortest grid distances and predecessors from sources, settled for every node
        within limit_m (nodes beyond it may be settled too: callers use only those within).

        The first search from a set of sources stops at limit_m. A node's distance does not
        depend on the limit (a limit only leaves farther nodes unsettled), nor does the
        predecessor scipy's search gives it (tests/test_planner.py holds it to that), so when
        the same sources come again (an oracle trying goals for a meeting from one spot) the
        whole grid is searched once and the later goals reuse it.
        """
        key = (band.ids, tuple(sources))
        kept = self._searches.get(key)
        if kept is not None and limit_m <= kept.limit_m:
            return kept.dist, kept.pred
        # scipy on first use: every `mavswarm` command imports the oracle (the task editor
        # derives plans), few of them plan a path.
        from scipy.sparse.csgraph import dijkstra
        if kept is not None:
            limit_m = math.inf
        dist, pred, _ = dijkstra(grid.graph, directed=True, indices=sources,
                                 return_predecessors=True, min_only=True, limit=limit_m)
        _keep(self._searches, key, SEARCHES_KEPT, _Search(limit_m, dist, pred))
        return dist, pred

    def _attach(self, grid: _Grid, point: Point3, z_m: float, *, leaving: bool) -> list[int]:
        """Grid nodes joined to point by a clear straight leg (point -> cell when leaving)."""
        px, py = point[0], point[1]
        cell = self.cell_m
        ix = min(max(math.floor((px - grid.x0_m) / cell), 0), grid.nx - 1)
        iy = min(max(math.floor((py - grid.y0_m) / cell), 0), grid.ny - 1)
        radius = math.ceil(self.clearance_m / cell) + 2
        tried: set[int] = set()
        found: list[int] = []
        while True:
            x_lo, x_hi = max(ix - radius, 0), min(ix + radius + 1, grid.nx)
            y_lo, y_hi = max(iy - radius, 0), min(iy + radius + 1, grid.ny)
            window = grid.node[y_lo:y_hi, x_lo:x_hi]
            wy, wx = np.nonzero(window >= 0)
            cx = grid.x0_m + (wx + x_lo + 0.5) * cell
            cy = grid.y0_m + (wy + y_lo + 0.5) * cell
            order = np.argsort(np.hypot(cx - px, cy - py), kind="stable")
            for k in order.tolist():
                n = int(window[wy[k], wx[k]])
                if n in tried:
                    continue
                tried.add(n)
                c = (float(cx[k]), float(cy[k]), z_m)
                leg = (point, c) if leaving else (c, point)
                if self.world.first_blockage(*leg) is None:
                    found.append(n)
                    if len(found) >= _ATTACH_WANTED:
                        return found
                if len(tried) >= _ATTACH_MAX_TRIES:
                    return found
            whole = x_lo == 0 and y_lo == 0 and x_hi == grid.nx and y_hi == grid.ny
            if found or whole:
                return found
            radius *= 2

    # ------------------------------------------------------------ clearance
    def _soft_ok(self, a: Point3, b: Point3) -> bool:
        """Leg a -> b keeps the soft clearance from obstacles blocking its lower end's altitude.

        Near an endpoint that is itself closer than that, the leg may not come any closer.
        """
        band = self._band(min(a[2], b[2]), VERTICAL_SLACK_M)
        if band.tree is None:
            return True
        line = shapely.LineString([a[:2], b[:2]]) if a[:2] != b[:2] else shapely.Point(a[:2])
        ids = band.tree.query(line, predicate="dwithin", distance=self._soft_m)
        if ids.size == 0:
            return True
        polys = band.footprints[ids]
        need = np.full(ids.size, self._soft_m)
        for end in (a, b):
            need = np.minimum(need, shapely.distance(shapely.Point(end[:2]), polys))
        return bool(np.all(shapely.distance(line, polys) >= need - _EPS_M))

    def _leg_ok(self, a: Point3, b: Point3) -> bool:
        return self.world.first_blockage(a, b) is None and self._soft_ok(a, b)


def _remember(kept: OrderedDict[K, V], key: K, most: int, build: Callable[[], V]) -> V:
    """kept[key], built first when missing (a build that raises stores nothing); only the
    `most` used last are kept."""
    value = kept.get(key)
    if value is not None:
        kept.move_to_end(key)
        return value
    return _keep(kept, key, most, build())


def _keep(kept: OrderedDict[K, V], key: K, most: int, value: V) -> V:
    """kept[key] = value as the one used last; only the `most` used last are kept."""
    kept[key] = value
    kept.move_to_end(key)
    while len(kept) > most:
        kept.popitem(last=False)
    return value


def _grid_graph(node: np.ndarray, cell_of_node: np.ndarray, cell_m: float
                ) -> scipy.sparse.csr_matrix:
    """8-connected directed graph between free cells (both directions of every edge)."""
    import scipy.sparse
    nx = node.shape[1]
    row = nx + 2
    padded = np.pad(node, 1, constant_values=-1).ravel()
    at = cell_of_node + (cell_of_node // nx) * 2 + row + 1  # each free cell in padded
    steps = [(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dy or dx]
    neighbours = np.stack([padded[at + (dy * row + dx)] for dy, dx in steps], axis=1)
    weights = np.array([cell_m * math.hypot(dy, dx) for dy, dx in steps])
    linked = neighbours >= 0
    indptr = np.zeros(cell_of_node.size + 1, dtype=np.int32)
    # a row's eight flags (one byte each) as one 64-bit word: its set bits count its edges
    np.cumsum(np.bitwise_count(linked.view(np.uint64).ravel()), out=indptr[1:])
    data = np.broadcast_to(weights, neighbours.shape)[linked]
    n = cell_of_node.size
    return scipy.sparse.csr_matrix((data, neighbours[linked], indptr), shape=(n, n))


def _string_pull(points: list[Point3], ok: Callable[[Point3, Point3], bool]) -> list[Point3]:
    """Few waypoints (after points[0]) along a polyline whose consecutive legs are all clear.

    From each anchor it gallops forward to a far point with a clear leg (every accepted leg is
    checked), then drops any waypoint whose neighbours see each other.
    """
    last = len(points) - 1
    chosen: list[int] = []
    a = 0
    while a < last:
        lo, step = a + 1, 1
        while lo < last:
            hi = min(lo + step, last)
            if ok(points[a], points[hi]):
                lo, step = hi, step * 2
                continue
            while hi - lo > 1:
                mid = (lo + hi) // 2
                if ok(points[a], points[mid]):
                    lo = mid
                else:
                    hi = mid
            break
        chosen.append(lo)
        a = lo
    route = [points[0]] + [points[i] for i in chosen]
    i = 1
    while i < len(route) - 1:
        if ok(route[i - 1], route[i + 1]):
            del route[i]
        else:
            i += 1
    return route[1:]
