"""Sensor model: geometry distance for targets and obstacles, centre distance for vehicles."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from emulator.perception import VEHICLE_KIND, Perception, SensedEntity, Sensor
from emulator.world import Obstacle, Target, World


def _ids(entities: tuple[SensedEntity, ...]) -> list[str]:
    return [e.id for e in entities]


def test_worked_example_disc_edge_and_polygon_edge() -> None:
    circle = Target.disc("c", "circle", "circle", (300.0, 100.0, 0.0), 30.0)
    # Nearest edge (x = 440) 40 m east of the drone; the centre is 60 m away.
    square = Target.polygon("p", "square", [(440, 80), (480, 80), (480, 120), (440, 120)])
    sensor = Sensor(World(targets=[circle, square]))
    seen = sensor.sense((400.0, 100.0, 20.0), 50.0)
    assert _ids(seen.targets) == ["p"]
    assert seen.targets[0].distance_m == pytest.approx(40.0, abs=1e-9)
    assert seen.targets[0].kind == "polygon"
    assert seen.targets[0].position_m == (460.0, 100.0, 0.0)
    # The circle is 70 m away at its edge: perceived only with a 70 m radius.
    wider = sensor.sense((400.0, 100.0, 20.0), 70.0)
    assert _ids(wider.targets) == ["p", "c"]
    assert wider.targets[1].distance_m == pytest.approx(70.0, abs=1e-9)


def test_polygon_partly_inside_the_radius_counts() -> None:
    big = Target.polygon("big", "field", [(30, -500), (1000, -500), (1000, 500), (30, 500)])
    sensor = Sensor(World(targets=[big]))
    seen = sensor.sense((0.0, 0.0, 0.0), 40.0)
    assert _ids(seen.targets) == ["big"]
    assert seen.targets[0].distance_m == pytest.approx(30.0)
    assert sensor.sense((0.0, 0.0, 0.0), 29.0).targets == ()


def test_inside_a_target_or_obstacle_is_distance_zero() -> None:
    area = Target.disc("a", "area", "circle", (0.0, 0.0, 0.0), 100.0)
    wall = Obstacle.disc("w", "wall", (5.0, 0.0), 10.0, height_m=3.0)
    seen = Sensor(World(targets=[area], obstacles=[wall])).sense((4.0, 0.0, 50.0), 0.0)
    assert [(e.id, e.distance_m) for e in seen.targets] == [("a", 0.0)]
    assert [(e.id, e.distance_m) for e in seen.obstacles] == [("w", 0.0)]


def test_disc_targets_use_the_edge_distance() -> None:
    fixed = Target.disc("f", "flag", "fixed", (55.0, 0.0, 0.0), 10.0)
    station = Target.disc("s", "pad", "waypoint", (0.0, 61.0, 0.0), 10.0, charge_rate_pct_s=0.5)
    seen = Sensor(World(targets=[fixed, station])).sense((0.0, 0.0, 30.0), 50.0)
    assert _ids(seen.targets) == ["f"]  # 45 m to its edge; the pad's edge is 51 m away
    assert seen.targets[0].distance_m == pytest.approx(45.0, abs=1e-9)


def test_obstacle_footprints_ellipse_orientation() -> None:
    ellipse = Obstacle.ellipse("e", "ellipse", (0.0, 0.0), 30.0, 10.0, height_m=5.0)
    sensor = Sensor(World(obstacles=[ellipse]))
    north = sensor.sense((0.0, 50.0, 0.0), 45.0)
    east = sensor.sense((70.0, 0.0, 0.0), 45.0)
    assert north.obstacles[0].distance_m == pytest.approx(40.0, abs=1e-9)
    assert east.obstacles[0].distance_m == pytest.approx(40.0, abs=1e-9)
    assert sensor.sense((0.0, 60.0, 0.0), 45.0).obstacles == ()
    assert sensor.sense((80.0, 0.0, 0.0), 45.0).obstacles == ()
    seen = north.obstacles[0]
    assert (seen.kind, seen.position_m) == ("ellipse", (0.0, 0.0, 0.0))


def test_distance_is_horizontal() -> None:
    capped = Obstacle.disc("c", "c", (0.0, 0.0), 5.0, height_m=2.0)
    flag = Target.disc("t", "t", "fixed", (20.0, 0.0, 0.0), 1.0)
    seen = Sensor(World(obstacles=[capped], targets=[flag])).sense((10.0, 0.0, 400.0), 10.0)
    assert _ids(seen.obstacles) == ["c"] and _ids(seen.targets) == ["t"]


def test_vehicles_by_centre_distance_excluding_the_observer() -> None:
    vehicles = {
        "me": (0.0, 0.0, 10.0),
        "b": (30.0, 40.0, 90.0),  # exactly 50 m horizontally, far above: counts
        "a": (-50.0, 0.0, 0.0),  # also 50 m: ties sort by id
        "near": (3.0, 4.0, 10.0),
        "far": (50.0, 1.0, 10.0),
    }
    sensor = Sensor(World())
    seen = sensor.sense((0.0, 0.0, 10.0), 50.0, vehicles=vehicles, exclude_vehicle="me")
    assert _ids(seen.vehicles) == ["near", "a", "b"]
    assert [v.distance_m for v in seen.vehicles] == pytest.approx([5.0, 50.0, 50.0])
    assert all(v.kind == VEHICLE_KIND for v in seen.vehicles)
    assert seen.vehicles[2].position_m == (30.0, 40.0, 90.0)
    with_me = sensor.sense((0.0, 0.0, 10.0), 50.0, vehicles=vehicles)
    assert _ids(with_me.vehicles)[0] == "me"
    assert sensor.sense((0.0, 0.0, 10.0), 50.0).vehicles == ()


def test_results_sorted_by_distance_then_id() -> None:
    targets = [Target.disc(f"t{k}", "t", "fixed", (10.0 * k, 0.0, 0.0), 1.0)
               for k in (5, 1, 3, 4, 2)]
    targets.append(Target.disc("t0", "twin", "fixed", (0.0, 20.0, 0.0), 1.0))
    targets.append(Target.disc("t00", "twin", "fixed", (0.0, -20.0, 0.0), 1.0))
    seen = Sensor(World(targets=targets)).sense((0.0, 0.0, 0.0), 100.0)
    assert _ids(seen.targets) == ["t1", "t0", "t00", "t2", "t3", "t4", "t5"]


def test_empty_world_and_bad_radius() -> None:
    sensor = Sensor(World())
    assert sensor.sense((0.0, 0.0, 0.0), 100.0) == Perception((), (), ())
    with pytest.raises(ValueError, match="perceived_radius_m"):
        sensor.sense((0.0, 0.0, 0.0), -1.0)


_RNG = np.random.default_rng(11)
_TARGETS: list[Target] = []
_OBSTACLES: list[Obstacle] = []
for _k in range(60):
    _x, _y = _RNG.uniform(0, 600, 2)
    if _k % 3 == 0:
        _TARGETS.append(Target.polygon(f"t{_k}", "p", [(_x, _y), (_x + 40, _y),
                                                      (_x + 20, _y + 30)]))
    else:
        _TARGETS.append(Target.disc(f"t{_k}", "d", ("fixed", "circle")[_k % 2], (_x, _y, 0.0),
                                    _RNG.uniform(0, 40)))
    _x, _y = _RNG.uniform(0, 600, 2)
    _OBSTACLES.append(Obstacle.ellipse(f"o{_k}", "e", (_x, _y), _RNG.uniform(2, 30),
                                       _RNG.uniform(2, 30)) if _k % 2
                      else Obstacle.disc(f"o{_k}", "c", (_x, _y), _RNG.uniform(2, 30)))
_SENSOR = Sensor(World(targets=_TARGETS, obstacles=_OBSTACLES))
_VEHICLES = {f"v{k}": (float(x), float(y), 10.0) for k, (x, y) in
             enumerate(_RNG.uniform(0, 600, (40, 2)))}


@settings(max_examples=150, deadline=None)
@given(st.floats(-50, 650), st.floats(-50, 650), st.floats(0, 250))
def test_exactly_the_entities_in_range(x: float, y: float, radius: float) -> None:
    seen = _SENSOR.sense((x, y, 30.0), radius, vehicles=_VEHICLES, exclude_vehicle="v0")
    point = shapely.Point(x, y)

    def expected(pairs: list[tuple[str, float]]) -> list[str]:
        return [i for d, i in sorted((d, i) for i, d in pairs if d <= radius)]

    assert _ids(seen.targets) == expected([(t.id, point.distance(t.geometry)) for t in _TARGETS])
    assert _ids(seen.obstacles) == expected(
        [(o.id, point.distance(o.footprint)) for o in _OBSTACLES])
    assert _ids(seen.vehicles) == expected(
        [(i, math.hypot(p[0] - x, p[1] - y)) for i, p in _VEHICLES.items() if i != "v0"])
    for entity in seen.targets + seen.obstacles + seen.vehicles:
        assert 0.0 <= entity.distance_m <= radius
