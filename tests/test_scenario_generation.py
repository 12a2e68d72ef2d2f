"""Seeded scenario generation: determinism, level counts, placement clearances and loading."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import random
import subprocess
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import shapely
from shapely import affinity

from benchmark.authoring.scenarios import (
    FAMILIES,
    LEVELS,
    PlacementError,
    all_session_keys,
    generate_world,
    level_spec,
    session_id,
    session_seed,
)
from benchmark.authoring.scenarios.families import RESILIENCE_FIXED_TARGETS, TRACKING_TARGETS
from benchmark.authoring.scenarios.placement import Layout, ShapeTemplate, clearance_m
from emulator.scenario import CHARGE_AMOUNT_PERIOD_S, WIND_DIRECTIONS_DEG, scenario_from_dict

Session = dict[str, Any]
REPO = Path(__file__).resolve().parents[1]

# The level table of the brief: drones, targets (target_assignment, area), obstacles, map side.
TABLE = {
    "easy": (3, 5, 3, 6, 600),
    "intermediate": (6, 12, 4, 15, 800),
    "moderate": (10, 25, 6, 30, 1000),
    "hard": (16, 50, 8, 60, 1200),
    "extreme": (30, 100, 10, 100, 1500),
}
TOP_KEYS = ["schema", "id", "family", "level", "index", "seed", "name", "description",
            "task_type", "map_size_m", "safety_margin_m", "origin", "environment", "drones",
            "targets", "obstacles", "tasks"]


@pytest.fixture(scope="module")
def worlds() -> dict[tuple[str, str, int], Session]:
    """All 125 sessions, generated once."""
    return {key: generate_world(*key) for key in all_session_keys()}


def _dump(session: Session) -> str:
    return json.dumps(session, sort_keys=True)


# ---------------------------------------------------------------- keys, seeds, determinism


def test_session_keys_and_ids() -> None:
    keys = all_session_keys()
    assert len(keys) == 125 and len(set(keys)) == 125
    assert keys[0] == ("area_search", "easy", 1)
    assert keys[5] == ("area_search", "intermediate", 1)
    assert keys[74] == ("target_assignment", "extreme", 5)
    assert keys[99] == ("target_tracking", "extreme", 5)
    assert keys[-1] == ("resilience", "extreme", 5)
    assert {f for f, _, _ in keys} == set(FAMILIES) and {lv for _, lv, _ in keys} == set(LEVELS)
    assert session_id("target_assignment", "hard", 3) == "target_assignment-hard-3"


def test_session_seed_is_sha256_of_the_key() -> None:
    digest = hashlib.sha256(b"mavswarm/area_search/easy/1").digest()
    assert session_seed("area_search", "easy", 1) == int.from_bytes(digest[:8], "big") >> 11
    seeds = {session_seed(*key) for key in all_session_keys()}
    assert len(seeds) == 125
    assert all(0 <= s < 2**53 for s in seeds)


@pytest.mark.slow
def test_same_key_gives_identical_json(worlds: dict[tuple[str, str, int], Session]) -> None:
    for key in [("area_search", "easy", 1), ("area_assignment_and_patrol", "hard", 4),
                ("target_assignment", "extreme", 2)]:
        assert _dump(generate_world(*key)) == _dump(worlds[key])


def test_identical_json_in_a_fresh_interpreter_with_another_hash_seed(
        worlds: dict[tuple[str, str, int], Session]) -> None:
    code = ("import json; from benchmark.authoring.scenarios import generate_world; "
            "print(json.dumps(generate_world('area_assignment_and_patrol', 'moderate', 5), "
            "sort_keys=True))")
    env = {**os.environ, "PYTHONHASHSEED": "12345"}
    out = subprocess.run([sys.executable, "-c", code], cwd=REPO, env=env, check=True,
                         capture_output=True, text=True).stdout.strip()
    assert out == _dump(worlds["area_assignment_and_patrol", "moderate", 5])


def test_different_keys_give_different_worlds(
        worlds: dict[tuple[str, str, int], Session]) -> None:
    def layout(session: Session) -> str:
        return json.dumps([session["drones"], session["targets"], session["obstacles"]])

    assert len({layout(w) for w in worlds.values()}) == 125
    a, b = worlds["area_search", "easy", 1], worlds["area_search", "easy", 2]
    assert a["seed"] != b["seed"] and a["drones"] != b["drones"]


# ---------------------------------------------------------------------------- bad inputs


@pytest.mark.parametrize(("family", "level", "index", "named"), [
    ("area_serch", "easy", 1, "'area_serch'"),
    ("", "easy", 1, "''"),
    ("target_trackin", "easy", 1, "'target_trackin'"),
    ("area_search", "Easy", 1, "'Easy'"),
    ("area_search", "impossible", 1, "'impossible'"),
    ("area_search", "easy", 0, "got 0"),
    ("area_search", "easy", 6, "got 6"),
    ("area_search", "easy", True, "got True"),
    ("area_search", "easy", "1", "got '1'"),
    ("area_search", "easy", 1.0, "got 1.0"),
])
def test_bad_keys_raise_value_error_naming_the_value(family: Any, level: Any, index: Any,
                                                     named: str) -> None:
    for function in (generate_world, session_seed, session_id):
        with pytest.raises(ValueError, match=named):
            function(family, level, index)


def test_level_spec_table_and_bad_level() -> None:
    assert LEVELS == ("easy", "intermediate", "moderate", "hard", "extreme")
    assert FAMILIES == ("area_search", "area_assignment_and_patrol", "target_assignment",
                        "target_tracking", "resilience")
    for level, (drones, fixed, area, obstacles, side) in TABLE.items():
        spec = level_spec(level)
        assert (spec.drone_count, spec.target_assignment_target_count, spec.area_target_count,
                spec.obstacle_count, spec.map_width_m, spec.map_height_m) == (
                    drones, fixed, area, obstacles, side, side)
        assert spec.charging_station_count == (1 if level in ("easy", "intermediate") else 2)
    with pytest.raises(dataclasses.FrozenInstanceError):
        level_spec("easy").drone_count = 4  # type: ignore[misc]
    with pytest.raises(ValueError, match="'medium'"):
        level_spec("medium")


# ------------------------------------------------------------------------ layout and counts


def test_every_world_has_the_layout_and_exact_counts(
        worlds: dict[tuple[str, str, int], Session]) -> None:
    for (family, level, index), w in worlds.items():
        drones, fixed, area, obstacles, side = TABLE[level]
        stations = 1 if level in ("easy", "intermediate") else 2
        assert list(w) == TOP_KEYS
        assert (w["schema"], w["family"], w["level"], w["index"]) == (
            "mavswarm.session/1", family, level, index)
        assert w["id"] == f"{family}-{level}-{index}" and w["tasks"] == []
        assert w["seed"] == session_seed(family, level, index)
        assert w["task_type"] == ("others" if family == "resilience" else family)
        assert w["map_size_m"] == [side, side]
        assert f"{side} x {side} m" in w["description"]
        assert w["name"].endswith(f", {level}, #{index}")
        assert len(w["drones"]) == drones and len(w["obstacles"]) == obstacles
        kinds = Counter(t["type"] for t in w["targets"])
        assert kinds["waypoint"] == stations
        if family == "target_tracking":
            main = TRACKING_TARGETS[level]
            assert len(w["targets"]) == main + stations
            assert kinds["moving"] == round(0.7 * main) and kinds["fixed"] == main - kinds[
                "moving"]
            continue
        if family == "resilience":
            assert len(w["targets"]) == area + RESILIENCE_FIXED_TARGETS[level]
            assert kinds["circle"] + kinds["polygon"] == area - stations
            assert kinds["fixed"] == RESILIENCE_FIXED_TARGETS[level]
            continue
        assert len(w["targets"]) == (fixed if family == "target_assignment" else area)
        if family == "target_assignment":
            assert kinds["fixed"] == fixed - stations
        else:
            assert kinds["circle"] + kinds["polygon"] == area - stations
        for prefix, items in (("d", w["drones"]), ("t", w["targets"]), ("o", w["obstacles"])):
            assert [e["id"] for e in items] == [f"{prefix}{k}" for k in range(1, len(items) + 1)]
            assert len({e["name"] for e in items}) == len(items)


def test_target_names_follow_the_family(worlds: dict[tuple[str, str, int], Session]) -> None:
    expected = {"area_search": "Search Area", "area_assignment_and_patrol": "Patrol Zone",
                "target_assignment": "Target"}
    for (family, _, _), w in worlds.items():
        main = [t for t in w["targets"] if t["type"] != "waypoint"]
        if family == "target_tracking":
            movers = [t["name"] for t in main if t["type"] == "moving"]
            fixed = [t["name"] for t in main if t["type"] == "fixed"]
            assert movers == [f"Moving Target {k}" for k in range(1, len(movers) + 1)]
            assert fixed == [f"Fixed Target {k}" for k in range(1, len(fixed) + 1)]
            continue
        if family == "resilience":
            areas = [t["name"] for t in main if t["type"] != "fixed"]
            fixed = [t["name"] for t in main if t["type"] == "fixed"]
            assert areas == [f"Search Area {k}" for k in range(1, len(areas) + 1)]
            assert fixed == [f"Target {k}" for k in range(1, len(fixed) + 1)]
            continue
        stations = [t for t in w["targets"] if t["type"] == "waypoint"]
        assert [t["name"] for t in main] == [f"{expected[family]} {k}"
                                             for k in range(1, len(main) + 1)]
        assert [t["name"] for t in stations] == [f"Charging Station {k}"
                                                 for k in range(1, len(stations) + 1)]


def _numbers(value: Any) -> list[float]:
    if isinstance(value, dict):
        return [n for v in value.values() for n in _numbers(v)]
    if isinstance(value, list):
        return [n for v in value for n in _numbers(v)]
    return [float(value)] if isinstance(value, int | float) else []


def test_coordinates_are_rounded_to_a_decimetre(
        worlds: dict[tuple[str, str, int], Session]) -> None:
    for w in worlds.values():
        for entity in w["drones"] + w["targets"] + w["obstacles"]:
            for field in ("position", "home_position", "vertices", "radius", "width", "length"):
                for number in _numbers(entity.get(field, [])):
                    assert abs(number * 10.0 - round(number * 10.0)) < 1e-6, (entity, field)


# ------------------------------------------------------------------------------ entity specs


def test_drone_specs(worlds: dict[tuple[str, str, int], Session]) -> None:
    for (_, level, _), w in worlds.items():
        varied = level in ("hard", "extreme")
        for d in w["drones"]:
            assert d["position"] == d["home_position"] and d["position"]["z"] == 0.0
            assert d["heading"] == 0.0 and d["battery_level"] == 100.0
            assert isinstance(d["max_speed"], int) and 12 <= d["max_speed"] <= 20
            assert d["max_altitude"] == 120
            assert 4000.0 <= d["battery_capacity"] <= 6000.0
            assert d["model"].startswith("MS-")
            for field, bounds in (("perceived_radius", (40, 60)), ("task_radius", (15, 25))):
                value = d[field]
                assert isinstance(value, int)
                if varied:
                    assert bounds[0] <= value <= bounds[1]
                else:
                    assert value == {"perceived_radius": 50, "task_radius": 20}[field]
    hard = [d["task_radius"] for w in worlds.values() if w["level"] == "hard"
            for d in w["drones"]]
    assert len(set(hard)) > 3


def test_environment_is_plausible(worlds: dict[tuple[str, str, int], Session]) -> None:
    for w in worlds.values():
        env = w["environment"]
        assert env["weather"] in ("clear", "partly_cloudy", "cloudy", "windy")
        assert 0.0 <= env["wind_speed"] <= 6.0 and round(env["wind_speed"], 1) == env["wind_speed"]
        assert env["wind_direction"] in WIND_DIRECTIONS_DEG
        assert isinstance(env["temperature"], float) and isinstance(env["humidity"], float)
    assert len({w["environment"]["weather"] for w in worlds.values()}) == 4


def test_target_shapes_and_sizes(worlds: dict[tuple[str, str, int], Session]) -> None:
    polygon_sizes: set[int] = set()
    for (_, level, _), w in worlds.items():
        low, high = level_spec(level).area_size_m
        for t in w["targets"]:
            if t["type"] == "waypoint":
                assert 8.0 <= t["radius"] <= 12.0 and 20.0 <= t["charge_amount"] <= 50.0
            elif t["type"] == "fixed":
                assert 3.0 <= t["radius"] <= 10.0
            elif t["type"] == "moving":
                assert 3.0 <= t["radius"] <= 8.0 and 5.0 <= t["moving_duration"] <= 60.0
                assert ("velocity" in t) != ("moving_path" in t)
            elif t["type"] == "circle":
                assert low - 0.05 <= t["radius"] <= high + 0.05
            else:
                assert t["type"] == "polygon" and "position" not in t
                ring = shapely.Polygon([(v["x"], v["y"]) for v in t["vertices"]])
                assert ring.is_valid and 4 <= len(t["vertices"]) <= 8
                polygon_sizes.add(len(t["vertices"]))
                hull = ring.convex_hull
                assert ring.area >= 0.99 * hull.area  # convex up to the 0.1 m rounding
                (cx, cy), = ring.centroid.coords
                reach = max(math.hypot(v["x"] - cx, v["y"] - cy) for v in t["vertices"])
                assert reach <= 1.5 * high
        if level == "extreme":
            radii = [t["radius"] for t in w["targets"] if t["type"] == "circle"]
            assert all(r >= level_spec("extreme").area_size_m[0] - 0.05 for r in radii)
    assert {4, 8} <= polygon_sizes and len(polygon_sizes) >= 4


def _is_axis_aligned_square(vertices: list[dict[str, float]]) -> bool:
    xs, ys = {v["x"] for v in vertices}, {v["y"] for v in vertices}
    return (len(vertices) == 4 and len(xs) == 2 and len(ys) == 2
            and abs((max(xs) - min(xs)) - (max(ys) - min(ys))) <= 0.11)


def test_obstacle_shapes_sizes_and_heights(worlds: dict[tuple[str, str, int], Session]) -> None:
    heights: list[float] = []
    kinds_above_easy: set[str] = set()
    for (_, level, _), w in worlds.items():
        low, high = level_spec(level).obstacle_size_m
        for o in w["obstacles"]:
            heights.append(o["height"])
            assert o["height"] == 0.0 or 15.0 <= o["height"] <= 60.0
            if o["type"] == "circle":
                assert low - 0.05 <= o["radius"] <= high + 0.05
            elif o["type"] == "point":
                assert 2.0 <= o["radius"] <= 5.0
            elif o["type"] == "ellipse":
                assert low - 0.05 <= max(o["width"], o["length"]) <= high + 0.05
            else:
                assert o["type"] == "polygon"
                assert shapely.Polygon([(v["x"], v["y"]) for v in o["vertices"]]).is_valid
            if level == "easy":
                assert o["type"] in ("circle", "polygon")
                if o["type"] == "polygon":
                    assert _is_axis_aligned_square(o["vertices"])
            else:
                kind = o["type"]
                if kind == "polygon":
                    kind = "square" if _is_axis_aligned_square(o["vertices"]) else "other"
                kinds_above_easy.add(kind)
    assert kinds_above_easy == {"circle", "ellipse", "point", "square", "other"}
    walls = sum(h == 0.0 for h in heights) / len(heights)
    assert 0.62 <= walls <= 0.78


# -------------------------------------------------------------------------- placement checks


def _disc(x: float, y: float, r: float) -> shapely.Polygon:
    return shapely.Point(x, y).buffer(r, quad_segs=64)


def _shape(entity: dict[str, Any]) -> shapely.Geometry:
    """The entity's footprint built straight from its dict."""
    if "vertices" in entity:
        return shapely.Polygon([(v["x"], v["y"]) for v in entity["vertices"]])
    x, y = entity["position"]["x"], entity["position"]["y"]
    if entity["type"] == "ellipse":
        return affinity.scale(_disc(x, y, 1.0), entity["width"], entity["length"])
    return _disc(x, y, entity["radius"])


def _pairs_closer_than(a: list[shapely.Geometry], b: list[shapely.Geometry] | None,
                      distance_m: float) -> list[tuple[int, int, float]]:
    """(i, j, distance) of geometries of a and b (or two different ones of a) closer than
    distance_m."""
    others = a if b is None else b
    if not a or not others:
        return []
    tree = shapely.STRtree(others)
    i, j = tree.query(a, predicate="dwithin", distance=distance_m)
    if b is None:
        i, j = i[i < j], j[i < j]
    gaps = shapely.distance(np.array(a)[i], np.array(others)[j]) if i.size else np.empty(0)
    return [(int(p), int(q), float(g)) for p, q, g in zip(i, j, gaps, strict=True)
            if g < distance_m]


def test_clearances_between_everything(worlds: dict[tuple[str, str, int], Session]) -> None:
    for key, w in worlds.items():
        obstacles = [_shape(o) for o in w["obstacles"]]
        targets = [_shape(t) for t in w["targets"]]
        drones = [shapely.Point(d["position"]["x"], d["position"]["y"]) for d in w["drones"]]
        assert _pairs_closer_than(obstacles, None, 25.0) == [], key
        assert _pairs_closer_than(targets, obstacles, 15.0) == [], key
        assert _pairs_closer_than(targets, None, 10.0) == [], key
        assert _pairs_closer_than(drones, obstacles, 20.0) == [], key
        assert _pairs_closer_than(drones, None, 8.0) == [], key
        assert _pairs_closer_than(drones, targets, 10.0) == [], key  # outside, 10 m clear


def test_the_clearance_check_sees_violations() -> None:
    a, b, far = _disc(0.0, 0.0, 10.0), _disc(30.0, 0.0, 10.0), _disc(100.0, 0.0, 10.0)
    assert [(i, j) for i, j, _ in _pairs_closer_than([a, b, far], None, 10.5)] == [(0, 1)]
    assert _pairs_closer_than([a, b, far], None, 9.5) == []
    assert [(i, j) for i, j, _ in _pairs_closer_than([shapely.Point(0, 0)], [b, far], 21.0)] \
        == [(0, 0)]


def test_everything_inside_the_map_with_margin(
        worlds: dict[tuple[str, str, int], Session]) -> None:
    for key, w in worlds.items():
        width, height = w["map_size_m"]
        shapes = [_shape(e) for e in w["targets"] + w["obstacles"]]
        shapes += [shapely.Point(d["position"]["x"], d["position"]["y"]) for d in w["drones"]]
        x0, y0, x1, y1 = shapely.bounds(shapes).T
        assert x0.min() >= 20.0 - 1e-9 and y0.min() >= 20.0 - 1e-9, key
        assert x1.max() <= width - 20.0 + 1e-9 and y1.max() <= height - 20.0 + 1e-9, key


def test_drones_start_clustered_at_one_corner_base(
        worlds: dict[tuple[str, str, int], Session]) -> None:
    corners_used = set()
    for key, w in worlds.items():
        width, height = w["map_size_m"]
        xy = np.array([(d["position"]["x"], d["position"]["y"]) for d in w["drones"]])
        corners = [(60.0, 60.0), (width - 60.0, 60.0), (60.0, height - 60.0),
                   (width - 60.0, height - 60.0)]
        near = [c for c in corners if np.all(np.hypot(*(xy - c).T) <= 150.0)]
        assert len(near) == 1, key
        corners_used.add((near[0][0] == 60.0, near[0][1] == 60.0))
    assert len(corners_used) == 4


@pytest.mark.slow
def test_generated_worlds_load_and_drones_can_climb_out(
        worlds: dict[tuple[str, str, int], Session]) -> None:
    for key, w in worlds.items():
        scenario = scenario_from_dict(w, source=session_id(*key))
        world = scenario.world
        assert scenario.task_type == w["task_type"] and scenario.name == w["name"]
        assert [v.id for v in scenario.vehicles] == [d["id"] for d in w["drones"]]
        assert len(world.targets) == len(w["targets"])
        assert len(world.obstacles) == len(w["obstacles"])
        assert world.wind.speed_m_s == w["environment"]["wind_speed"]
        for t in w["targets"]:
            if t["type"] == "waypoint":
                rate = world.target(t["id"]).charge_rate_pct_s
                assert rate == pytest.approx(t["charge_amount"] / CHARGE_AMOUNT_PERIOD_S)
        for o in w["obstacles"]:
            assert world.obstacle(o["id"]).height_m == o["height"]
        for v in scenario.vehicles:
            x, y, z = v.position_m
            assert z == 0.0
            assert world.first_blockage((x, y, 0.0), (x, y, 30.0)) is None, (key, v.id)


# ----------------------------------------------------------------------- the layout itself


def test_layout_keeps_group_clearances() -> None:
    assert clearance_m("obstacle", "obstacle") == 25.0
    assert clearance_m("target", "obstacle") == clearance_m("obstacle", "target") == 15.0
    assert clearance_m("drone", "drone") == 8.0
    layout = Layout(400.0, 400.0)
    layout.add("obstacle", ShapeTemplate.disc(10.0).at(100.0, 100.0))
    # Disc gap 24.9 m: too close for an obstacle, enough for a target.
    near = ShapeTemplate.disc(10.0).at(144.9, 100.0)
    assert not layout.fits("obstacle", near) and layout.fits("target", near)
    assert layout.fits("obstacle", ShapeTemplate.disc(10.0).at(145.2, 100.0))
    square = ShapeTemplate.polygon([(-10, -10), (10, -10), (10, 10), (-10, 10)])
    assert not layout.fits("obstacle", square.at(144.0, 100.0))
    assert layout.fits("obstacle", square.at(145.2, 100.0))
    # Outside the 20 m margin.
    assert not layout.fits("target", ShapeTemplate.disc(10.0).at(25.0, 200.0))
    with pytest.raises(ValueError, match="'wall'"):
        layout.fits("wall", near)


def test_layout_raises_when_nothing_fits() -> None:
    layout = Layout(100.0, 100.0)
    with pytest.raises(PlacementError, match="big thing"):
        layout.place(random.Random(1), "obstacle", lambda s: ShapeTemplate.disc(40.0 + 10 * s),
                     label="big thing")
    placed = layout.place(random.Random(1), "obstacle",
                          lambda s: ShapeTemplate.disc(25.0 * s + 5.0), label="shrinking thing")
    assert placed.radius_m == 20.0  # radius 30 cannot fit in the 60 m free square; 20 can
