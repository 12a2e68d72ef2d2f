"""Oracle path planning and coverage sweeps: every planned leg passes collision prevention."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence

import numpy as np
import pytest
import shapely
import shapely.affinity

from emulator.world import Obstacle, World, ellipse_polygon
from swarm_agents.oracle.coverage import lawnmower, order_visits, split_lanes
from swarm_agents.oracle.planner import GRIDS_KEPT, NoPath, PathPlanner

Point3 = tuple[float, float, float]


def _legs(start: Sequence[float], route: Sequence[Sequence[float]]
          ) -> list[tuple[Sequence[float], Sequence[float]]]:
    return list(zip([start, *route[:-1]], route, strict=True))


def _assert_flyable(world: World, start: Point3, goal: Point3, route: list[Point3]) -> None:
    assert route, "a route has at least the goal"
    assert route[-1] == goal
    for a, b in _legs(start, route):
        assert world.first_blockage(a, b) is None, f"leg {a} -> {b} is blocked"


def _length_m(start: Sequence[float], route: Sequence[Sequence[float]]) -> float:
    return sum(math.dist(a, b) for a, b in _legs(start, route))


def _min_distance_m(world: World, route: Sequence[Point3], start: Point3) -> float:
    lines = [shapely.LineString([a[:2], b[:2]]) for a, b in _legs(start, route)]
    return min(float(shapely.distance(o.footprint, line))
               for o in world.obstacles for line in lines)


def _wall(id: str, x0: float, x1: float, y0: float, y1: float, height_m: float = 0.0
          ) -> Obstacle:
    return Obstacle.polygon(id, id, [(x0, y0), (x1, y0), (x1, y1), (x0, y1)], height_m=height_m)


def _random_world(seed: int, count: int = 30, size_m: float = 600.0) -> World:
    rng = np.random.default_rng(seed)
    obstacles = []
    for i in range(count):
        c = (float(rng.uniform(0, size_m)), float(rng.uniform(0, size_m)))
        r = float(rng.uniform(4.0, 60.0))
        h = float(rng.choice([0.0, 0.0, 15.0, 35.0]))
        kind = int(rng.integers(0, 3))
        if kind == 0:
            obstacles.append(Obstacle.disc(f"o{i}", "o", c, r, height_m=h))
        elif kind == 1:
            obstacles.append(Obstacle.ellipse(f"o{i}", "o", c, r, float(rng.uniform(4, 60)),
                                              height_m=h))
        else:
            a = float(rng.uniform(0, math.pi))
            d, w = np.array([math.cos(a), math.sin(a)]), float(rng.uniform(2.0, 15.0))
            p = np.array([-d[1], d[0]])
            v = [tuple((np.array(c) + sx * r * d + sy * w * p).tolist()) for sx, sy in
                 ((1, 1), (-1, 1), (-1, -1), (1, -1))]
            obstacles.append(Obstacle.polygon(f"o{i}", "o", v, height_m=h))
    return World(obstacles=obstacles)


DISC = Obstacle.disc("disc", "tower", (0.0, 0.0), 30.0)


# ------------------------------------------------------------------------------ planning


def test_straight_line_when_clear() -> None:
    world = World(obstacles=[Obstacle.disc("far", "far", (0.0, 500.0), 20.0)])
    planner = PathPlanner(world)
    goal = (100.0, 10.0, 30.0)
    assert planner.plan((-100.0, 0.0, 30.0), goal) == [goal]
    assert planner.plan((-100.0, 0.0, 0.0), goal) == [goal]
    assert PathPlanner(World()).plan((0.0, 0.0, 5.0), goal) == [goal]


def test_goes_around_a_disc_to_the_sky() -> None:
    world = World(obstacles=[DISC])
    start, goal = (-100.0, 0.0, 20.0), (100.0, 0.0, 20.0)
    assert world.first_blockage(start, goal) is not None
    route = PathPlanner(world).plan(start, goal)
    _assert_flyable(world, start, goal, route)
    assert 2 <= len(route) <= 4
    assert all(abs(p[2] - 20.0) < 1e-9 for p in route)
    # Hugging the disc at a few metres costs little over the straight 200 m.
    assert _length_m(start, route) < 225.0
    # Away from start and goal the legs keep clear of the 2 m safety margin.
    assert _min_distance_m(world, route, start) > 2.9


def test_goes_around_a_long_polygon_wall() -> None:
    world = World(obstacles=[_wall("wall", -5.0, 5.0, -200.0, 150.0)])
    start, goal = (-50.0, 0.0, 15.0), (50.0, 0.0, 15.0)
    route = PathPlanner(world).plan(start, goal)
    _assert_flyable(world, start, goal, route)
    # The short way round is past the wall's north end.
    assert max(p[1] for p in route) > 150.0
    assert _length_m(start, route) < 2 * math.hypot(50.0, 160.0) + 20.0


def test_capped_obstacle_flown_over_high_and_avoided_low() -> None:
    world = World(obstacles=[Obstacle.disc("block", "block", (0.0, 0.0), 30.0, height_m=20.0)])
    planner = PathPlanner(world)
    high = (100.0, 0.0, 40.0)
    assert planner.plan((-100.0, 0.0, 40.0), high) == [high]
    low = (100.0, 0.0, 10.0)
    route = planner.plan((-100.0, 0.0, 10.0), low)
    assert len(route) >= 2
    _assert_flyable(world, (-100.0, 0.0, 10.0), low, route)


def test_climb_from_the_ground_beside_a_capped_obstacle_is_vertical() -> None:
    world = World(obstacles=[Obstacle.disc("block", "block", (0.0, 0.0), 20.0, height_m=20.0)])
    start, goal = (-30.0, 0.0, 0.0), (60.0, 0.0, 40.0)
    assert world.first_blockage(start, goal) is not None
    route = PathPlanner(world).plan(start, goal)
    assert route == [(-30.0, 0.0, 40.0), goal]
    _assert_flyable(world, start, goal, route)


def test_descent_blocked_by_a_roof_happens_at_the_goal() -> None:
    world = World(obstacles=[Obstacle.disc("roof", "roof", (0.0, 0.0), 30.0, height_m=20.0)])
    start, goal = (0.0, 0.0, 30.0), (80.0, 0.0, 5.0)
    route = PathPlanner(world).plan(start, goal)
    _assert_flyable(world, start, goal, route)
    assert route[-2] == (80.0, 0.0, 30.0)


def test_routing_grids_kept_are_bounded_and_rebuilt_alike() -> None:
    # Walls of five heights make five altitude bands; a session's planner used to keep every
    # band's grid (an extreme-level world's: about 10 MB each) for the whole session.
    heights = (10.0, 20.0, 30.0, 40.0, 0.0)
    world = World(obstacles=[_wall(f"w{i}", 100.0 * i - 5.0, 100.0 * i + 5.0, -150.0, 150.0,
                                   height_m=h) for i, h in enumerate(heights)])
    planner = PathPlanner(world)
    queries = [((-50.0, 0.0, z), (450.0, 0.0, z)) for z in (5.0, 15.0, 25.0, 35.0, 45.0)]
    first = [planner.plan(start, goal) for start, goal in queries]
    assert len(planner._grids) <= GRIDS_KEPT < len(queries)
    planner._routes.clear()  # plan again, through grids built again
    for (start, goal), route in zip(queries, first, strict=True):
        _assert_flyable(world, start, goal, route)
        assert planner.plan(start, goal) == route == PathPlanner(world).plan(start, goal)
    assert len(planner._grids) <= GRIDS_KEPT


def test_a_route_asked_again_is_remembered_and_handed_out_anew() -> None:
    world = World(obstacles=[DISC])
    planner = PathPlanner(world)
    start, goal = (-100.0, 0.0, 10.0), (100.0, 0.0, 10.0)
    route = planner.plan(start, goal)
    assert len(route) > 1  # around the disc
    route.append((0.0, 0.0, 0.0))  # the caller's list is its own
    again = planner.plan(start, goal)
    assert again == PathPlanner(world).plan(start, goal) == route[:-1]
    assert len(planner._routes) == 1
    # -0.0 is another key (a route ends exactly at its goal, sign of zero included)
    assert math.copysign(1.0, planner.plan(start, (100.0, -0.0, 10.0))[-1][1]) == -1.0


def test_clearance_checks_alone_build_no_grid() -> None:
    world = World(obstacles=[Obstacle.disc("far", "far", (0.0, 500.0), 20.0)])
    planner = PathPlanner(world)
    goal = (100.0, 10.0, 30.0)
    assert planner.plan((-100.0, 0.0, 30.0), goal) == [goal]
    assert not planner._grids


@pytest.mark.parametrize("gap_m", [0.8, 4.0])
def test_start_inside_the_clearance_zone(gap_m: float) -> None:
    # gap 0.8: inside the 2 m safety margin; gap 4: outside it but inside the 6 m clearance.
    world = World(obstacles=[DISC])
    start, goal = (-30.0 - gap_m, 0.0, 20.0), (60.0, 5.0, 20.0)
    route = PathPlanner(world).plan(start, goal)
    _assert_flyable(world, start, goal, route)


def test_goal_inside_the_clearance_zone_and_start_outside_the_grid() -> None:
    world = World(obstacles=[DISC])
    start, goal = (-3000.0, 20.0, 20.0), (34.0, 0.0, 20.0)
    route = PathPlanner(world).plan(start, goal)
    _assert_flyable(world, start, goal, route)


def test_no_path_into_a_ring_of_obstacles() -> None:
    ring = [Obstacle.disc(f"r{i}", "r", (60.0 * math.cos(a), 60.0 * math.sin(a)), 12.0)
            for i, a in enumerate(np.linspace(0.0, 2 * math.pi, 24, endpoint=False))]
    planner = PathPlanner(World(obstacles=ring))
    with pytest.raises(NoPath):
        planner.plan((-200.0, 0.0, 20.0), (0.0, 0.0, 20.0))
    # A capped ring can be flown over.
    capped = World(obstacles=[Obstacle.disc(o.id, "r", o.center_m, 12.0, height_m=10.0)
                              for o in ring])
    start, goal = (-200.0, 0.0, 20.0), (0.0, 0.0, 20.0)
    _assert_flyable(capped, start, goal, PathPlanner(capped).plan(start, goal))


def test_no_path_to_a_goal_inside_an_obstacle() -> None:
    planner = PathPlanner(World(obstacles=[DISC]))
    with pytest.raises(NoPath, match="inside an obstacle"):
        planner.plan((-100.0, 0.0, 20.0), (5.0, 5.0, 20.0))


def test_leg_clear_is_the_autopilot_test() -> None:
    planner = PathPlanner(World(obstacles=[DISC]))
    assert not planner.leg_clear((-100.0, 0.0, 20.0), (100.0, 0.0, 20.0))
    assert planner.leg_clear((-100.0, 40.0, 20.0), (100.0, 40.0, 20.0))
    assert not planner.leg_clear((-100.0, 31.0, 20.0), (100.0, 31.0, 20.0))  # in the margin


def test_plans_are_deterministic() -> None:
    world = _random_world(7)
    a, b = PathPlanner(world), PathPlanner(world)
    pairs = [((5.0, 5.0, 20.0), (590.0, 580.0, 20.0)), ((590.0, 10.0, 0.0), (10.0, 590.0, 10.0))]
    for start, goal in pairs:
        first = a.plan(start, goal)
        assert first == a.plan(start, goal) == b.plan(start, goal)


def test_goals_tried_from_one_spot_reuse_one_search_and_plan_alike() -> None:
    # A meeting tries goal after goal from one spot: the first search stops at its limit,
    # the second searches the whole grid, the rest reuse it; every route is the one a fresh
    # planner makes.
    world = _random_world(3, count=40)
    planner = PathPlanner(world)
    start = (10.0, 10.0, 20.0)
    # goals moving away (each a longer limit), then nearer ones
    goals = [(540.0 + 6.0 * k, 560.0 + 2.5 * k, 20.0) for k in range(8)] + [(300.0, 590.0, 20.0)]
    searched: list[float] = []
    search = planner._search

    def counted(band, grid, sources, limit_m):
        kept = planner._searches.get((band.ids, tuple(sources)))
        if kept is None or limit_m > kept.limit_m:
            searched.append(limit_m)
        return search(band, grid, sources, limit_m)

    planner._search = counted  # type: ignore[method-assign]
    for goal in goals:
        assert planner.plan(start, goal) == PathPlanner(world).plan(start, goal)
    assert len(searched) == 2  # the first goal's limited search, then the whole grid once
    (kept,) = planner._searches.values()
    assert kept.limit_m == math.inf


def test_a_search_settles_the_same_nodes_alike_whatever_its_limit() -> None:
    from scipy.sparse.csgraph import dijkstra
    world = _random_world(11, count=40)
    planner = PathPlanner(world)
    planner.plan((10.0, 10.0, 20.0), (590.0, 590.0, 20.0))
    (grid,) = planner._grids.values()
    sources = [0, 1, 2]
    full, full_pred = dijkstra(grid.graph, indices=sources, min_only=True,
                               return_predecessors=True)[:2]
    for limit_m in (50.0, 200.0, 400.0):
        dist, pred = dijkstra(grid.graph, indices=sources, min_only=True,
                              return_predecessors=True, limit=limit_m)[:2]
        settled = np.isfinite(dist)
        assert settled.sum() < np.isfinite(full).sum()
        assert np.array_equal(settled, full <= limit_m)
        assert np.array_equal(dist[settled], full[settled])
        assert np.array_equal(pred[settled], full_pred[settled])


def test_grid_graph_links_every_pair_of_free_neighbours() -> None:
    from swarm_agents.oracle.planner import _grid_graph
    rng = np.random.default_rng(5)
    free = rng.random((13, 17)) < 0.7
    cell_of_node = np.flatnonzero(free.ravel()).astype(np.int32)
    node = np.full(free.shape, -1, dtype=np.int32)
    node.ravel()[cell_of_node] = np.arange(cell_of_node.size, dtype=np.int32)
    graph = _grid_graph(node, cell_of_node, 4.0)
    rows: list[list[tuple[int, float]]] = []
    for flat in cell_of_node.tolist():
        iy, ix = divmod(flat, free.shape[1])
        row = []
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                y, x = iy + dy, ix + dx
                if (dy or dx) and 0 <= y < free.shape[0] and 0 <= x < free.shape[1] \
                        and free[y, x]:
                    row.append((int(node[y, x]), 4.0 * math.hypot(dy, dx)))
        rows.append(row)
    assert graph.indptr.tolist() == [0, *itertools.accumulate(len(r) for r in rows)]
    assert graph.indices.tolist() == [n for r in rows for n, _ in r]
    assert graph.data.tolist() == [w for r in rows for _, w in r]


@pytest.mark.slow
def test_random_worlds_every_leg_is_clear() -> None:
    planned = 0
    for seed in range(20):
        world = _random_world(seed)
        planner = PathPlanner(world)
        rng = np.random.default_rng(1000 + seed)
        for _ in range(4):
            start = (*rng.uniform(-20.0, 620.0, 2).tolist(), float(rng.choice([0.0, 20.0])))
            goal = (*rng.uniform(-20.0, 620.0, 2).tolist(), float(rng.choice([10.0, 20.0, 40.0])))
            try:
                route = planner.plan(start, goal)
            except NoPath:
                # Only a goal in or near an obstacle may be unreachable.
                assert any(o.footprint.distance(shapely.Point(goal[:2])) < 6.0
                           for o in world.obstacles if o.blocks_altitude(goal[2] - 3.0))
                continue
            _assert_flyable(world, start, goal, route)
            planned += 1
    assert planned >= 60


def test_bad_arguments_are_named() -> None:
    world = World(obstacles=[DISC])
    with pytest.raises(ValueError, match="clearance_m"):
        PathPlanner(world, clearance_m=3.0)
    with pytest.raises(ValueError, match="cell_m"):
        PathPlanner(world, cell_m=0.0)
    with pytest.raises(ValueError, match="goal_m"):
        PathPlanner(world).plan((0.0, 0.0, 0.0), (1.0, math.nan, 2.0))


# ------------------------------------------------------------------------------ coverage


def _covered_share(area: shapely.Geometry, path: Sequence[Point3], radius_m: float) -> float:
    corridor = shapely.LineString([p[:2] for p in path]).buffer(radius_m)
    return float(shapely.intersection(area, corridor).area / area.area)


SQUARE = shapely.box(0.0, 0.0, 100.0, 100.0)
ELLIPSE = shapely.affinity.rotate(ellipse_polygon((40.0, -20.0), 120.0, 45.0), 30.0)
L_SHAPE = shapely.Polygon([(0, 0), (200, 0), (200, 40), (40, 40), (40, 160), (0, 160)])


@pytest.mark.parametrize("area", [SQUARE, ELLIPSE, L_SHAPE], ids=["square", "ellipse", "L"])
@pytest.mark.parametrize("radius_m", [5.0, 12.0])
def test_lawnmower_covers_the_area(area: shapely.Polygon, radius_m: float) -> None:
    path = lawnmower(area, 25.0, 1.6 * radius_m)
    assert len(path) % 2 == 0
    assert all(p[2] == 25.0 for p in path)
    assert _covered_share(area, path, radius_m) >= 0.99
    # Lanes: consecutive pairs, parallel to each other.
    dirs = [np.subtract(path[i + 1][:2], path[i][:2]) for i in range(0, len(path), 2)]
    for d in dirs:
        cross = d[0] * dirs[0][1] - d[1] * dirs[0][0]
        assert abs(cross) < 1e-6 * (1 + np.linalg.norm(d) * np.linalg.norm(dirs[0]))


def test_lawnmower_lane_positions_and_start() -> None:
    path = lawnmower(SQUARE, 10.0, 16.0, start_xy=(120.0, 120.0))
    lanes = [path[i:i + 2] for i in range(0, len(path), 2)]
    along_x = all(abs(a[1] - b[1]) < 1e-9 for a, b in lanes)
    offsets = sorted(a[1] if along_x else a[0] for a, _ in lanes)
    assert offsets == pytest.approx([8.0, 24.0, 40.0, 56.0, 72.0, 88.0, 92.0])
    ends = [path[0], path[1], path[-2], path[-1]]
    nearest = min(ends, key=lambda p: math.dist(p[:2], (120.0, 120.0)))
    assert path[0] == nearest
    assert math.dist(path[0][:2], (100.0, 92.0)) < 1e-6 or math.dist(
        path[0][:2], (92.0, 100.0)) < 1e-6


def test_lawnmower_rejects_bad_input() -> None:
    with pytest.raises(ValueError, match="spacing_m"):
        lawnmower(SQUARE, 10.0, 0.0)
    with pytest.raises(ValueError, match="area"):
        lawnmower(shapely.Point(0, 0), 10.0, 5.0)


@pytest.mark.parametrize("n", [1, 2, 3, 5, 40])
def test_split_lanes_pieces_join_back_into_the_sweep(n: int) -> None:
    sweep = lawnmower(ELLIPSE, 20.0, 16.0)
    pieces = split_lanes(sweep, n)
    assert len(pieces) == n
    for a, b in itertools.pairwise(pieces):
        assert a[-1] == b[0]
    joined = [*pieces[0], *(p for piece in pieces[1:] for p in piece[1:])]
    original = set(sweep)
    assert [p for p in joined if p in original] == sweep
    # Added cut points lie on the sweep's legs.
    line = shapely.LineString([p[:2] for p in sweep])
    assert all(line.distance(shapely.Point(p[:2])) < 1e-6 for p in joined)
    lengths = [_length_m(piece[0], piece[1:]) if len(piece) > 1 else 0.0 for piece in pieces]
    total = _length_m(sweep[0], sweep[1:])
    assert sum(lengths) == pytest.approx(total)
    assert max(lengths) <= total / n * (1 + 2 * 0.05) + 1e-9


def test_split_lanes_rejects_bad_n() -> None:
    with pytest.raises(ValueError, match="n must"):
        split_lanes([(0.0, 0.0, 1.0), (1.0, 0.0, 1.0)], 0)
    assert split_lanes([(0.0, 0.0, 1.0), (1.0, 0.0, 1.0)], 1) == [[(0.0, 0.0, 1.0),
                                                                  (1.0, 0.0, 1.0)]]


def _tour_m(start: tuple[float, float], points: Sequence[tuple[float, float]],
            order: Sequence[int]) -> float:
    stops = [start, *(points[i] for i in order)]
    return sum(math.dist(a, b) for a, b in itertools.pairwise(stops))


def test_order_visits_is_a_short_permutation() -> None:
    assert order_visits((0.0, 0.0), []) == []
    line = [(30.0, 0.0), (10.0, 0.0), (20.0, 0.0), (40.0, 0.0)]
    assert order_visits((0.0, 0.0), line) == [1, 2, 0, 3]
    rng = np.random.default_rng(3)
    for _ in range(5):
        points = [tuple(p) for p in rng.uniform(0.0, 1000.0, (25, 2)).tolist()]
        order = order_visits((500.0, 500.0), points)
        assert sorted(order) == list(range(25))
        # 2-opt leaves no improving reversal: compare with a greedy-only tour's length.
        greedy: list[int] = []
        for _ in range(25):
            last = points[greedy[-1]] if greedy else (500.0, 500.0)
            dists = [(math.dist(last, points[i]), i) for i in range(25) if i not in greedy]
            greedy.append(min(dists)[1])
        assert _tour_m((500.0, 500.0), points, order) <= _tour_m((500.0, 500.0), points,
                                                                  greedy) + 1e-6
        for i in range(len(order) - 1):
            for j in range(i + 1, len(order)):
                flipped = order[:i] + order[i:j + 1][::-1] + order[j + 1:]
                assert _tour_m((500.0, 500.0), points, flipped) >= _tour_m(
                    (500.0, 500.0), points, order) - 1e-6
