"""World truth: footprints, heights, wind, containment and collision prevention."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from emulator.world import (
    CALM,
    RAW_STOP_BEFORE_M,
    Obstacle,
    Target,
    Wind,
    World,
    disc_polygon,
)

MARGIN_M = 2.0


def _distance_to(obstacle: Obstacle, point: tuple[float, ...]) -> float:
    return shapely.distance(obstacle.footprint, shapely.Point(point[0], point[1]))


def _square(id: str, x0: float, y0: float, side: float, height_m: float = 0.0) -> Obstacle:
    return Obstacle.polygon(id, id, [(x0, y0), (x0 + side, y0), (x0 + side, y0 + side),
                                     (x0, y0 + side)], height_m=height_m)


# ----------------------------------------------------------------------------- footprints


@pytest.mark.parametrize("radius_m", [0.5, 3.0, 20.0, 240.0])
def test_disc_footprint_area_and_extent(radius_m: float) -> None:
    obstacle = Obstacle.disc("c", "circle", (10.0, -5.0), radius_m)
    assert obstacle.kind == "circle"
    assert obstacle.footprint.area == pytest.approx(math.pi * radius_m**2, rel=1e-3)
    minx, miny, maxx, maxy = obstacle.footprint.bounds
    assert (minx, miny, maxx, maxy) == pytest.approx(
        (10 - radius_m, -5 - radius_m, 10 + radius_m, -5 + radius_m), abs=1e-9)
    assert len(obstacle.footprint.exterior.coords) - 1 >= 64
    assert obstacle.center_m == (10.0, -5.0)


def test_point_obstacle_is_a_disc() -> None:
    obstacle = Obstacle.disc("p", "point", (0.0, 0.0), 1.0, kind="point")
    assert obstacle.kind == "point"
    assert obstacle.footprint.area == pytest.approx(math.pi, rel=1e-3)


def test_ellipse_width_is_along_x_and_length_along_y() -> None:
    obstacle = Obstacle.ellipse("e", "ellipse", (100.0, 50.0), 30.0, 10.0)
    assert obstacle.footprint.area == pytest.approx(math.pi * 30.0 * 10.0, rel=1e-3)
    assert obstacle.footprint.bounds == pytest.approx((70.0, 40.0, 130.0, 60.0), abs=1e-9)
    assert obstacle.footprint.contains(shapely.Point(100.0 + 27.0, 50.0))
    assert not obstacle.footprint.contains(shapely.Point(100.0, 50.0 + 12.0))
    # (x/w)^2 + (y/l)^2 = 0.5 + 0.45 < 1 is inside; 0.5 + 0.55 > 1 is outside.
    assert obstacle.footprint.contains(shapely.Point(100 + 30 * math.sqrt(0.5),
                                                     50 + 10 * math.sqrt(0.45)))
    assert not obstacle.footprint.contains(shapely.Point(100 + 30 * math.sqrt(0.5),
                                                         50 + 10 * math.sqrt(0.55)))


def test_polygon_footprint_keeps_vertices_and_centre() -> None:
    obstacle = _square("s", 0.0, 0.0, 10.0, height_m=5.0)
    assert obstacle.footprint.area == pytest.approx(100.0)
    assert obstacle.center_m == (5.0, 5.0)
    assert obstacle.height_m == 5.0


def test_heights_block_altitudes() -> None:
    wall = Obstacle.disc("w", "wall", (0.0, 0.0), 5.0)
    capped = Obstacle.disc("c", "capped", (0.0, 0.0), 5.0, height_m=10.0)
    assert wall.blocks_altitude(0.0) and wall.blocks_altitude(10_000.0)
    assert capped.blocks_altitude(0.0) and capped.blocks_altitude(10.0)
    assert not capped.blocks_altitude(10.01)


@pytest.mark.parametrize(
    "build",
    [
        lambda: Obstacle.disc("x", "x", (0, 0), 0.0),
        lambda: Obstacle.disc("x", "x", (0, 0), 1.0, height_m=-1.0),
        lambda: Obstacle.disc("x", "x", (0, 0), 1.0, kind="blob"),
        lambda: Obstacle.ellipse("x", "x", (0, 0), 0.0, 3.0),
        lambda: Obstacle.polygon("x", "x", [(0, 0), (2, 2), (2, 0), (0, 2)]),
        lambda: Obstacle.polygon("x", "x", [(0, 0), (1, 1), (2, 2)]),
        lambda: Target.disc("t", "t", "fixed", (0, 0, 0), -1.0),
        lambda: Target.disc("t", "t", "waypoint", (0, 0, 0), 5.0),
        lambda: Target.disc("t", "t", "fixed", (0, 0, 0), 5.0, charge_rate_pct_s=1.0),
        lambda: Target.disc("t", "t", "ufo", (0, 0, 0), 5.0),
    ],
)
def test_invalid_entities_are_rejected(build: Callable[[], object]) -> None:
    with pytest.raises(ValueError):
        build()


def test_targets() -> None:
    dot = Target.disc("t", "dot", "fixed", (3.0, 4.0, 0.0), 0.0)
    assert dot.radius_m == 0.0
    assert dot.geometry.area == pytest.approx(math.pi * 0.01**2, rel=1e-3)
    assert not dot.is_area and not dot.is_charging_station
    station = Target.disc("s", "station", "waypoint", (0, 0, 0), 5.0, charge_rate_pct_s=0.5)
    assert station.is_charging_station and station.charge_rate_pct_s == 0.5
    area = Target.polygon("a", "area", [(0, 0, 0), (10, 0, 0), (10, 10, 0), (0, 10, 0)])
    assert area.is_area and area.position_m == (5.0, 5.0, 0.0) and area.radius_m == 1.0
    assert Target.disc("c", "circle", "circle", (0, 0, 0), 30.0).is_area


# ----------------------------------------------------------------------------------- wind


@pytest.mark.parametrize(
    ("from_deg", "expected"),
    [
        (0.0, (0.0, -1.0)),  # a north wind blows towards the south
        (90.0, (-1.0, 0.0)),  # an east wind blows towards the west
        (180.0, (0.0, 1.0)),
        (270.0, (1.0, 0.0)),
        (225.0, (math.sqrt(0.5), math.sqrt(0.5))),  # south-westerly: towards the north-east
        (360.0, (0.0, -1.0)),
    ],
)
def test_wind_vector_points_where_the_air_goes(
    from_deg: float, expected: tuple[float, float]
) -> None:
    vx, vy = Wind(4.0, from_deg).velocity_enu_m_s()
    assert (vx, vy) == pytest.approx((4.0 * expected[0], 4.0 * expected[1]), abs=1e-12)


def test_wind_validation_and_calm() -> None:
    assert CALM.velocity_enu_m_s() == pytest.approx((0.0, 0.0))
    assert Wind(1.0, -90.0).from_direction_deg == 270.0
    with pytest.raises(ValueError):
        Wind(-1.0, 0.0)
    with pytest.raises(ValueError):
        Wind(1.0, math.nan)


# ---------------------------------------------------------------------------------- world


def test_lookup_and_unique_ids() -> None:
    obstacle = Obstacle.disc("o1", "rock", (0, 0), 1.0)
    target = Target.disc("t1", "flag", "fixed", (50, 0, 0), 1.0)
    world = World(obstacles=[obstacle], targets=[target])
    assert world.obstacle("o1") is obstacle and world.target("t1") is target
    assert world.obstacles == (obstacle,) and world.targets == (target,)
    assert world.safety_margin_m == 2.0 and world.wind == CALM
    with pytest.raises(KeyError, match="no obstacle with id 'nope'"):
        world.obstacle("nope")
    with pytest.raises(KeyError, match="no target with id 'o1'"):
        world.target("o1")
    with pytest.raises(ValueError, match="obstacle ids must be unique"):
        World(obstacles=[obstacle, obstacle])
    with pytest.raises(ValueError, match="safety_margin_m"):
        World(safety_margin_m=-1.0)


def test_charging_station_at() -> None:
    near = Target.disc("s1", "near", "waypoint", (0, 0, 0), 10.0, charge_rate_pct_s=0.4)
    far = Target.disc("s2", "far", "waypoint", (15, 0, 0), 10.0, charge_rate_pct_s=0.4)
    fixed = Target.disc("f", "fixed", "fixed", (100, 0, 0), 10.0)
    world = World(targets=[near, far, fixed])
    assert world.charging_station_at(1.0, 0.0) is near
    assert world.charging_station_at(10.0, 0.0) is far  # both contain it; far's centre is nearer
    assert world.charging_station_at(0.0, 10.0) is near  # on the rim counts
    assert world.charging_station_at(0.0, 10.5) is None
    assert world.charging_station_at(100.0, 0.0) is None  # not a station


# ------------------------------------------------------------------------ inside_obstacles

_WORLD_FOR_POINTS = World(obstacles=[
    Obstacle.disc("c1", "c1", (0.0, 0.0), 10.0),
    Obstacle.disc("c2", "c2", (8.0, 0.0), 6.0, height_m=5.0),  # overlaps c1
    Obstacle.ellipse("e", "e", (-20.0, 10.0), 8.0, 3.0, height_m=12.0),
    _square("s1", 5.0, 5.0, 10.0, height_m=20.0),
    _square("s2", -15.0, -15.0, 5.0),
    Obstacle.polygon("u", "u", [(20, -20), (30, -20), (30, 0), (27, 0), (27, -17), (23, -17),
                                (23, 0), (20, 0)], height_m=7.0),
])


def _inside_reference(world: World, x: float, y: float, z: float) -> bool:
    point = shapely.Point(x, y)
    return any(o.blocks_altitude(z) and shapely.intersects(o.footprint, point)
               for o in world.obstacles)


_coordinate = st.one_of(st.integers(-35, 35).map(float),
                        st.floats(-35.0, 35.0, allow_nan=False, allow_infinity=False))


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(_coordinate, _coordinate, st.sampled_from([0.0, 4.9, 5.0, 7.0, 12.0,
                                                                      20.0, 20.5, 99.0])),
                min_size=1, max_size=40))
@pytest.mark.slow
def test_inside_obstacles_matches_per_point_shapely(
    points: list[tuple[float, float, float]],
) -> None:
    x, y, z = (np.array(c, dtype=float) for c in zip(*points, strict=True))
    mask = _WORLD_FOR_POINTS.inside_obstacles(x, y, z)
    expected = [_inside_reference(_WORLD_FOR_POINTS, *p) for p in points]
    assert mask.tolist() == expected
    assert [_WORLD_FOR_POINTS.clearance_ok(*p) for p in points[:5]] == [
        not e for e in expected[:5]]


def test_inside_obstacles_keeps_shape_boundaries_and_heights() -> None:
    x = np.array([[0.0, 10.0], [8.0, 100.0]])
    y = np.zeros((2, 2))
    mask = _WORLD_FOR_POINTS.inside_obstacles(x, y, np.array(3.0))
    assert mask.shape == (2, 2)
    assert mask.tolist() == [[True, True], [True, False]]  # (10, 0) lies on c1's rim
    assert _WORLD_FOR_POINTS.inside_obstacles(np.array([14.0]), np.array([0.0]),
                                              np.array([5.0])).tolist() == [True]
    assert _WORLD_FOR_POINTS.inside_obstacles(np.array([14.0]), np.array([0.0]),
                                              np.array([5.1])).tolist() == [False]
    assert World().inside_obstacles(np.zeros(3), np.zeros(3), np.zeros(3)).tolist() == [False] * 3


# -------------------------------------------------------------------------- first_blockage


def test_straight_path_through_a_circle_stops_at_the_margin() -> None:
    circle = Obstacle.disc("c", "c", (0.0, 0.0), 20.0)
    world = World(obstacles=[circle])
    blockage = world.first_blockage((-100.0, 0.0, 10.0), (100.0, 0.0, 10.0))
    assert blockage is not None and blockage.obstacle is circle
    assert _distance_to(circle, blockage.stop_m) == pytest.approx(MARGIN_M, abs=0.01)
    assert blockage.stop_m[0] == pytest.approx(-22.0, abs=0.01)
    assert blockage.stop_m[1:] == (0.0, 10.0)
    assert blockage.fraction == pytest.approx((blockage.stop_m[0] + 100.0) / 200.0)


@pytest.mark.parametrize("angle_deg", [0.0, 13.0, 45.0, 90.0, 137.0, 200.0, 271.0])
def test_approach_from_any_direction_stops_at_the_margin(angle_deg: float) -> None:
    circle = Obstacle.disc("c", "c", (5.0, 7.0), 12.0)
    world = World(obstacles=[circle], safety_margin_m=3.0)
    a = math.radians(angle_deg)
    start = (5.0 + 80.0 * math.cos(a), 7.0 + 80.0 * math.sin(a), 20.0)
    blockage = world.first_blockage(start, (5.0, 7.0, 20.0))
    assert blockage is not None
    assert _distance_to(circle, blockage.stop_m) == pytest.approx(3.0, abs=0.01)


def test_path_beside_the_obstacle_is_clear_but_inside_the_margin_is_not() -> None:
    world = World(obstacles=[Obstacle.disc("c", "c", (0.0, 0.0), 20.0)])
    assert world.first_blockage((-100.0, 22.5, 5.0), (100.0, 22.5, 5.0)) is None
    assert world.first_blockage((-100.0, 21.0, 5.0), (100.0, 21.0, 5.0)) is not None
    # Ending short of the margin zone is clear.
    assert world.first_blockage((-100.0, 0.0, 5.0), (-22.5, 0.0, 5.0)) is None


def test_height_zero_blocks_at_any_altitude() -> None:
    world = World(obstacles=[Obstacle.disc("w", "w", (0.0, 0.0), 5.0)])
    assert world.first_blockage((-50.0, 0.0, 900.0), (50.0, 0.0, 900.0)) is not None


def test_path_above_a_capped_obstacle_is_clear() -> None:
    world = World(obstacles=[Obstacle.disc("c", "c", (0.0, 0.0), 20.0, height_m=10.0)])
    assert world.first_blockage((-100.0, 0.0, 12.1), (100.0, 0.0, 12.1)) is None
    assert world.first_blockage((-100.0, 0.0, 12.0), (100.0, 0.0, 12.0)) is not None
    assert world.first_blockage((-100.0, 0.0, 8.0), (100.0, 0.0, 8.0)) is not None


def test_climbing_path_clears_a_capped_obstacle_when_high_enough() -> None:
    world = World(obstacles=[Obstacle.disc("c", "c", (0.0, 0.0), 10.0, height_m=10.0)])
    # z reaches 12 (height + margin) at x = -12 + 0.2 * 100, i.e. past the zone's entry at x=-12.
    assert world.first_blockage((-100.0, 0.0, 0.0), (100.0, 0.0, 24.0)) is not None
    # Climbing steeply, z passes 12 at x = -94: clear over the top.
    assert world.first_blockage((-100.0, 0.0, 0.0), (100.0, 0.0, 400.0)) is None


def test_descending_onto_a_capped_obstacle_stops_at_height_plus_margin() -> None:
    capped = Obstacle.disc("c", "c", (0.0, 0.0), 20.0, height_m=10.0)
    world = World(obstacles=[capped])
    blockage = world.first_blockage((3.0, 4.0, 30.0), (3.0, 4.0, 0.0))
    assert blockage is not None and blockage.obstacle is capped
    assert blockage.stop_m == pytest.approx((3.0, 4.0, 12.0), abs=1e-9)
    assert blockage.fraction == pytest.approx(18.0 / 30.0)
    # Climbing away from the top is clear.
    assert world.first_blockage((3.0, 4.0, 12.0), (3.0, 4.0, 50.0)) is None
    # A further descent from the margin stops just above the raw top.
    again = world.first_blockage(blockage.stop_m, (3.0, 4.0, 0.0))
    assert again is not None
    assert again.stop_m[2] == pytest.approx(10.0 + RAW_STOP_BEFORE_M, abs=1e-9)


def test_start_inside_the_margin_zone() -> None:
    circle = Obstacle.disc("c", "c", (0.0, 0.0), 20.0)
    world = World(obstacles=[circle])
    start = (-21.0, 0.0, 5.0)  # 1 m from the obstacle, inside the 2 m margin
    assert world.first_blockage(start, (-100.0, 0.0, 5.0)) is None  # moving away
    assert world.first_blockage(start, (-21.0, 80.0, 5.0)) is None  # tangent, leaving
    towards = world.first_blockage(start, (100.0, 0.0, 5.0))
    assert towards is not None and towards.obstacle is circle
    assert _distance_to(circle, towards.stop_m) == pytest.approx(RAW_STOP_BEFORE_M, abs=1e-3)
    assert not circle.footprint.intersects(shapely.LineString([start[:2], towards.stop_m[:2]]))


def test_vehicle_stopped_at_the_margin_does_not_creep_into_the_obstacle() -> None:
    circle = Obstacle.disc("c", "c", (0.0, 0.0), 20.0)
    world = World(obstacles=[circle])
    position: tuple[float, float, float] = (-100.0, 1.0, 5.0)
    goal = (100.0, 1.0, 5.0)
    stops = []
    for _ in range(5):
        blockage = world.first_blockage(position, goal)
        assert blockage is not None
        position = blockage.stop_m
        stops.append(position)
        assert _distance_to(circle, position) > 0.04
    for later in stops[2:]:
        assert later == pytest.approx(stops[1], abs=1e-9)


def test_spawned_inside_the_margin_can_take_off() -> None:
    world = World(obstacles=[Obstacle.disc("c", "c", (0.0, 0.0), 20.0, height_m=10.0)])
    assert world.first_blockage((-21.0, 0.0, 0.0), (-21.0, 0.0, 30.0)) is None


def test_polygon_obstacle_face_corner_and_grazing() -> None:
    square = _square("s", 0.0, 0.0, 10.0)
    world = World(obstacles=[square])
    face = world.first_blockage((-20.0, 5.0, 0.0), (30.0, 5.0, 0.0))
    assert face is not None and face.stop_m == pytest.approx((-2.0, 5.0, 0.0), abs=1e-9)
    corner = world.first_blockage((-20.0, -20.0, 0.0), (30.0, 30.0, 0.0))
    assert corner is not None
    assert _distance_to(square, corner.stop_m) == pytest.approx(MARGIN_M, abs=0.01)
    # Exactly at margin distance along a face is a graze, not a blockage; closer is blocked.
    assert world.first_blockage((-20.0, -2.0, 0.0), (30.0, -2.0, 0.0)) is None
    assert world.first_blockage((-20.0, -1.99, 0.0), (30.0, -1.99, 0.0)) is not None


def test_concave_polygon_gap_and_reentry() -> None:
    # A U open to the north: a 10 m wide slot between x = 25 and x = 35.
    u_shape = Obstacle.polygon("u", "u", [(0, 0), (60, 0), (60, 50), (35, 50), (35, 10),
                                          (25, 10), (25, 50), (0, 50)])
    world = World(obstacles=[u_shape])
    assert world.first_blockage((30.0, 100.0, 1.0), (30.0, 13.0, 1.0)) is None  # down the slot
    bottom = world.first_blockage((30.0, 100.0, 1.0), (30.0, -100.0, 1.0))
    assert bottom is not None and bottom.stop_m[1] == pytest.approx(12.0, abs=1e-9)
    # Across the arms, starting inside the slot: blocked at the east arm's margin.
    across = world.first_blockage((30.0, 30.0, 1.0), (100.0, 30.0, 1.0))
    assert across is not None and across.stop_m[0] == pytest.approx(33.0, abs=1e-9)


def test_earliest_of_several_obstacles_wins() -> None:
    near = Obstacle.disc("near", "near", (0.0, 0.0), 5.0)
    far = _square("far", 40.0, -5.0, 10.0)
    for obstacles in ([near, far], [far, near]):
        blockage = World(obstacles=obstacles).first_blockage((-50.0, 0.0, 3.0), (90.0, 0.0, 3.0))
        assert blockage is not None and blockage.obstacle.id == "near"
        east = World(obstacles=obstacles).first_blockage((90.0, 0.0, 3.0), (-50.0, 0.0, 3.0))
        assert east is not None and east.obstacle.id == "far"
        assert east.stop_m[0] == pytest.approx(52.0)


def test_degenerate_segments() -> None:
    world = World(obstacles=[Obstacle.disc("c", "c", (0.0, 0.0), 10.0, height_m=5.0)])
    assert world.first_blockage((50.0, 0.0, 1.0), (50.0, 0.0, 1.0)) is None
    assert world.first_blockage((0.0, 0.0, 6.0), (0.0, 0.0, 6.0)) is None
    inside = world.first_blockage((1.0, 1.0, 4.0), (1.0, 1.0, 4.0))
    assert inside is not None and inside.fraction == 0.0 and inside.stop_m == (1.0, 1.0, 4.0)
    assert World().first_blockage((0.0, 0.0, 0.0), (10.0, 0.0, 0.0)) is None


def test_zero_margin_stops_on_the_footprint() -> None:
    circle = Obstacle.disc("c", "c", (0.0, 0.0), 10.0)
    blockage = World(obstacles=[circle], safety_margin_m=0.0).first_blockage(
        (-50.0, 0.0, 0.0), (50.0, 0.0, 0.0))
    assert blockage is not None and blockage.stop_m[0] == pytest.approx(-10.0)


# Property checks against shapely on random worlds.

_RNG = np.random.default_rng(7)
_RANDOM_OBSTACLES = []
for _k in range(40):
    _cx, _cy = _RNG.uniform(-300, 300, 2)
    _h = float(_RNG.choice([0.0, 10.0, 25.0]))
    if _k % 3 == 0:
        _RANDOM_OBSTACLES.append(Obstacle.disc(f"o{_k}", "d", (_cx, _cy), _RNG.uniform(3, 25),
                                               height_m=_h))
    elif _k % 3 == 1:
        _RANDOM_OBSTACLES.append(Obstacle.ellipse(f"o{_k}", "e", (_cx, _cy),
                                                  _RNG.uniform(3, 25), _RNG.uniform(3, 25),
                                                  height_m=_h))
    else:
        _RANDOM_OBSTACLES.append(_square(f"o{_k}", _cx, _cy, _RNG.uniform(5, 40), height_m=_h))
_RANDOM_WORLD = World(obstacles=_RANDOM_OBSTACLES)
_FOOTPRINTS = np.array([o.footprint for o in _RANDOM_OBSTACLES])
# The world's own buffered footprints: this checks the crossing arithmetic, not the buffers.
_BUFFERED = list(_RANDOM_WORLD._buffered)

_xy = st.floats(-350.0, 350.0, allow_nan=False, allow_infinity=False)
_z = st.sampled_from([0.0, 5.0, 11.0, 12.0, 20.0, 30.0, 100.0])


@settings(max_examples=200, deadline=None)
@given(_xy, _xy, _xy, _xy, _z)
def test_level_flight_matches_shapely_entry(
    x0: float, y0: float, x1: float, y1: float, z: float
) -> None:
    start = shapely.Point(x0, y0)
    zone = [b for b, o in zip(_BUFFERED, _RANDOM_OBSTACLES, strict=True)
            if o.height_m == 0.0 or z <= o.height_m + MARGIN_M]
    if any(shapely.distance(b, start) < 1e-5 for b in zone) or (x0, y0) == (x1, y1):
        return  # starts in (or right at) a margin zone: another rule applies
    line = shapely.LineString([(x0, y0), (x1, y1)])
    direction = np.array([x1 - x0, y1 - y0])
    entries = []
    for buffered in zone:
        piece = line.intersection(buffered)
        if piece.length > 1e-6:
            coords = shapely.get_coordinates(piece) - (x0, y0)
            entries.append(float(np.min(coords @ direction)) / float(direction @ direction))
    blockage = _RANDOM_WORLD.first_blockage((x0, y0, z), (x1, y1, z))
    if not entries:
        assert blockage is None
        return
    assert blockage is not None
    assert blockage.fraction * line.length == pytest.approx(min(entries) * line.length, abs=1e-6)


def _check_flown_part(x0: float, y0: float, z0: float, x1: float, y1: float, z1: float) -> None:
    """Outside the margin zone a vehicle keeps the margin; inside it, it keeps out of the raw
    volume of the obstacle whose zone it started in."""
    if not _RANDOM_WORLD.clearance_ok(x0, y0, z0):
        return
    near = [_distance_to(o, (x0, y0)) for o in _RANDOM_OBSTACLES]
    if any(abs(d - MARGIN_M) < 0.01 for d in near):
        return  # ambiguous start right on a margin boundary
    in_zone = [d <= MARGIN_M and (o.height_m == 0.0 or z0 <= o.height_m + MARGIN_M)
               for d, o in zip(near, _RANDOM_OBSTACLES, strict=True)]
    blockage = _RANDOM_WORLD.first_blockage((x0, y0, z0), (x1, y1, z1))
    t = np.linspace(0.0, 1.0 if blockage is None else blockage.fraction, 101)
    x, y, z = x0 + t * (x1 - x0), y0 + t * (y1 - y0), z0 + t * (z1 - z0)
    distance = shapely.distance(_FOOTPRINTS[:, None], shapely.points(x, y)[None, :])
    raw_only = np.array(in_zone)[:, None]
    heights = np.array([o.height_m for o in _RANDOM_OBSTACLES])[:, None]
    top = np.where(heights == 0.0, np.inf, heights + np.where(raw_only, 0.0, MARGIN_M))
    applies = z[None, :] <= top - 1e-6
    assert np.all(distance[applies & raw_only] > 0.0)
    assert np.all(distance[applies & ~raw_only] >= MARGIN_M - 0.01)


@settings(max_examples=100, deadline=None)
@given(_xy, _xy, _z, _xy, _xy, _z)
@pytest.mark.slow
def test_flown_part_never_enters_a_protected_volume(
    x0: float, y0: float, z0: float, x1: float, y1: float, z1: float
) -> None:
    _check_flown_part(x0, y0, z0, x1, y1, z1)


@settings(max_examples=100, deadline=None)
@given(st.integers(0, len(_RANDOM_OBSTACLES) - 1), st.floats(0.0, 1.0), st.floats(0.02, 3.0),
       _z, st.floats(0.0, 2.0 * math.pi), st.floats(1.0, 200.0), _z)
@pytest.mark.slow
def test_moves_starting_close_to_an_obstacle(
    k: int, along: float, offset_m: float, z0: float, heading_rad: float, length_m: float,
    z1: float,
) -> None:
    footprint = _RANDOM_OBSTACLES[k].footprint
    rim = footprint.exterior.interpolate(along, normalized=True)
    centre = footprint.centroid
    outward = np.array([rim.x - centre.x, rim.y - centre.y])
    x0, y0 = np.array([rim.x, rim.y]) + offset_m * outward / np.linalg.norm(outward)
    _check_flown_part(float(x0), float(y0), z0, float(x0 + length_m * math.cos(heading_rad)),
                      float(y0 + length_m * math.sin(heading_rad)), z1)


def test_disc_polygon_helper() -> None:
    disc = disc_polygon((1.0, 2.0), 3.0)
    assert disc.area == pytest.approx(math.pi * 9.0, rel=1e-3)
    assert disc.centroid.coords[0] == pytest.approx((1.0, 2.0))
