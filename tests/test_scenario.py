"""Scenarios: the reference session files, field defaults, malformed input and the defaults."""

from __future__ import annotations

import copy
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import shapely

from emulator.geo import DEFAULT_ORIGIN, GeoOrigin
from emulator.networks import MAX_FLEET_VEHICLES
from emulator.scenario import (
    CHARGE_AMOUNT_PERIOD_S,
    WIND_DIRECTIONS_DEG,
    ScenarioError,
    default_scenario,
    load_scenario,
    scenario_from_dict,
)

# The MultiUAV-Plat example sessions live in the shared folder beside the repository.
SESSIONS = Path(__file__).resolve().parents[2] / "shared" / "sessions"
AREA_SEARCH = SESSIONS / "Example_Session_Area_Search.json"
TARGET_ASSIGNMENT = SESSIONS / "Example_Session_Target_Assignment.json"
needs_examples = pytest.mark.skipif(
    not AREA_SEARCH.is_file(), reason=f"example sessions not found in {SESSIONS}"
)


# --------------------------------------------------------------------------- example files


@needs_examples
def test_area_search_example_loads() -> None:
    scenario = load_scenario(AREA_SEARCH)
    assert scenario.source == str(AREA_SEARCH)
    assert scenario.name == "Example Session (Area Search)"
    assert scenario.task_type == "area_search"
    assert len(scenario.vehicles) == 10
    assert len(scenario.world.targets) == 2 and len(scenario.world.obstacles) == 6
    drone = scenario.vehicles[0]
    assert (drone.id, drone.name, drone.model) == ("31e42431", "Drone 1", "Model-D4")
    # the file's home is in the air and its capacity a size label: both mapped, with notes
    assert drone.position_m == (174.0, 189.0, 9.0) and drone.home_m == (674.0, 689.0, 0.0)
    assert (drone.max_speed_m_s, drone.max_altitude_m) == (12.0, 102.0)
    assert (drone.perceived_radius_m, drone.task_radius_m) == (100.0, 10.0)
    assert (drone.battery_pct, drone.battery_capacity_mah) == (100.0, 8900.0)
    assert any("(id 31e42431).home_position.z 9 m" in n for n in scenario.notes)
    assert any("(id 31e42431).battery_capacity 89 is a MultiUAV-Plat size label" in n
               for n in scenario.notes)
    polygon = scenario.world.target("42d492ea")
    assert polygon.kind == "polygon" and polygon.is_area and polygon.radius_m == 1.0
    assert polygon.geometry.area == pytest.approx(235.0 * 234.0)
    assert polygon.position_m == (834.0, 501.0, 0.0)  # rounded vertex mean
    circle = scenario.world.target("b349d182")
    assert circle.kind == "circle" and circle.radius_m == 95.0
    assert circle.geometry.area == pytest.approx(math.pi * 95.0**2, rel=1e-3)
    ellipse = scenario.world.obstacle("35fcf445")
    assert ellipse.kind == "ellipse" and ellipse.height_m == 0.0
    assert ellipse.footprint.bounds == pytest.approx((470.0, 345.0, 570.0, 415.0))
    tower = scenario.world.obstacle("7dd93e96")
    assert tower.kind == "polygon" and tower.height_m == 70.0
    assert tower.footprint.area == pytest.approx(93.0 * 107.0)
    point = scenario.world.obstacle("7738e42e")
    assert point.kind == "point" and point.footprint.area == pytest.approx(math.pi * 2500, rel=1e-3)
    wind = scenario.world.wind
    assert (wind.speed_m_s, wind.from_direction_deg) == (2.5, 315.0)
    vx, vy = wind.velocity_enu_m_s()  # from the north-west: towards the south-east
    assert vx == pytest.approx(2.5 / math.sqrt(2)) and vy == pytest.approx(-2.5 / math.sqrt(2))
    assert scenario.world.origin == DEFAULT_ORIGIN
    assert scenario.world.safety_margin_m == 2.0


@needs_examples
def test_target_assignment_example_loads() -> None:
    scenario = load_scenario(str(TARGET_ASSIGNMENT))
    assert scenario.task_type == "target_assignment"
    assert len(scenario.vehicles) == 30
    assert len(scenario.world.targets) == 20 and len(scenario.world.obstacles) == 6
    assert {t.kind for t in scenario.world.targets} == {"fixed"}
    assert scenario.world.target("a3032c0b").radius_m == 10.0
    assert scenario.world.target("a3032c0b").position_m == (482.0, 443.0, 0.0)
    assert all(v.home_m == (*v.position_m[:2], 0.0) for v in scenario.vehicles)  # on the ground
    airborne = {v.name: v.position_m[2] for v in scenario.vehicles if v.position_m[2] > 0.0}
    assert airborne == {"Drone 6": 2.0, "Drone 12": 10.0, "Drone 24": 7.0, "Drone 29": 12.0}
    assert len({v.id for v in scenario.vehicles}) == 30
    point = scenario.world.obstacle("9a42f414")
    assert (point.kind, point.height_m, point.center_m) == ("point", 1.0, (320.0, 26.0))
    assert point.footprint.area == pytest.approx(math.pi * 400.0, rel=1e-3)
    assert scenario.world.wind.velocity_enu_m_s() == pytest.approx((0.0, -2.4))


# ------------------------------------------------------------------------ fields, defaults


def _minimal() -> dict[str, Any]:
    return {
        "name": "mini",
        "drones": [{"id": "a1", "name": "Drone 1", "model": "M", "max_speed": 10,
                    "max_altitude": 100, "battery_capacity": 80,
                    "position": {"x": 0, "y": 0, "z": 0}}],
        "targets": [{"id": "t1", "name": "T", "type": "fixed",
                     "position": {"x": 100, "y": 0}}],
        "obstacles": [{"id": "o1", "name": "O", "type": "circle", "radius": 10,
                       "position": {"x": 50, "y": 50}}],
    }


def test_reference_defaults() -> None:
    data = _minimal()
    del data["drones"][0]["id"]
    data["drones"][0]["position"] = {"x": 3, "y": 4}
    data["targets"].append({"name": "W", "type": "waypoint", "position": {"x": -50, "y": 0}})
    data["obstacles"].append({"name": "P", "type": "point", "position": {"x": -50, "y": -50}})
    scenario = scenario_from_dict(data, source="mini.json")
    drone = scenario.vehicles[0]
    assert drone.id == "d1"
    assert (drone.perceived_radius_m, drone.task_radius_m) == (50.0, 20.0)
    assert drone.battery_pct == 100.0 and drone.heading_deg == 0.0
    assert drone.position_m == (3.0, 4.0, 0.0) and drone.home_m == drone.position_m
    fixed, station = scenario.world.targets
    assert fixed.radius_m == 1.0 and fixed.charge_rate_pct_s is None
    assert station.is_charging_station and station.radius_m == 1.0
    assert station.charge_rate_pct_s == pytest.approx(25.0 / 60.0)
    assert CHARGE_AMOUNT_PERIOD_S == 60.0
    circle, point = scenario.world.obstacles
    assert circle.height_m == 10.0 and point.height_m == 10.0
    assert point.footprint.area == pytest.approx(math.pi, rel=1e-3)
    assert scenario.task_type == "others" and scenario.name == "mini"
    assert scenario.world.wind.speed_m_s == 0.0


def test_optional_fields_are_read() -> None:
    data = _minimal()
    drone = data["drones"][0]
    drone.update(heading=370, perceived_radius=120, task_radius=15, battery_level=150,
                 home_position={"x": 5, "y": 6, "z": 0}, status="flying")
    data["targets"].append({"id": "w", "name": "W", "type": "waypoint", "charge_amount": 30,
                            "radius": 8, "position": {"x": -60, "y": 0, "z": 0}, "capacity": 3})
    data["targets"].append({"id": "m", "name": "M", "type": "moving", "radius": 3,
                            "position": {"x": 0, "y": 90, "z": 4},
                            "velocity": {"x": 1, "y": 0, "z": 0}})
    data["obstacles"][0]["height"] = 0
    data.update(task_type="area_search", safety_margin_m=3.5,
                origin={"latitude_deg": -33.9, "longitude_deg": 151.2, "altitude_amsl_m": 20},
                environment={"wind_speed": 6, "wind_direction": "southwest"})
    scenario = scenario_from_dict(data)
    spec = scenario.vehicles[0]
    assert spec.heading_deg == 10.0 and spec.battery_pct == 100.0
    assert (spec.perceived_radius_m, spec.task_radius_m) == (120.0, 15.0)
    assert spec.home_m == (5.0, 6.0, 0.0)
    assert scenario.world.target("w").charge_rate_pct_s == pytest.approx(0.5)
    moving = scenario.world.target("m")
    assert moving.kind == "moving" and moving.position_m == (0.0, 90.0, 4.0)
    assert scenario.world.obstacle("o1").height_m == 0.0
    assert scenario.world.safety_margin_m == 3.5
    assert scenario.world.origin == GeoOrigin(-33.9, 151.2, 20.0)
    assert scenario.world.wind.from_direction_deg == 225.0
    assert scenario.task_type == "area_search" and scenario.source == "<dict>"


@pytest.mark.parametrize(
    ("battery", "expected_pct"),
    [
        ({"battery_volume": 40, "battery_level": 90}, 50.0),  # volume wins
        ({"battery_volume": 120}, 100.0),  # clamped to the capacity
        ({"battery_volume": -5}, 0.0),
        ({"battery_level": 35.5}, 35.5),
        ({"battery_level": 150}, 100.0),
        ({"battery_level": -3}, 0.0),
        ({"battery_volume": None, "battery_level": 20}, 20.0),
    ],
)
def test_battery_precedence(battery: dict[str, Any], expected_pct: float) -> None:
    data = _minimal()
    data["drones"][0].update(battery)
    assert scenario_from_dict(data).vehicles[0].battery_pct == pytest.approx(expected_pct)


@pytest.mark.parametrize("name", sorted(WIND_DIRECTIONS_DEG))
def test_wind_direction_names(name: str) -> None:
    data = _minimal()
    data["environment"] = {"wind_speed": 3.0, "wind_direction": name.upper()}
    wind = scenario_from_dict(data).world.wind
    assert wind.from_direction_deg == WIND_DIRECTIONS_DEG[name]
    vx, vy = wind.velocity_enu_m_s()
    towards = math.radians(WIND_DIRECTIONS_DEG[name] + 180.0)  # where the air goes
    assert (vx, vy) == pytest.approx((3.0 * math.sin(towards), 3.0 * math.cos(towards)))


def test_polygon_vertices_are_normalised() -> None:
    data = _minimal()
    ring = [{"x": 200, "y": 0}, {"x": 230, "y": 0}, {"x": 230, "y": 20}, {"x": 200, "y": 20},
            {"x": 200, "y": 0}]
    data["targets"].append({"id": "p", "name": "P", "type": "polygon",
                            "position": {"x": 200, "y": 0}, "vertices": ring})
    data["obstacles"].append({"id": "q", "name": "Q", "type": "polygon", "height": 5,
                              "vertices": [{"x": -200, "y": 0, "z": 0}, {"x": -170, "y": 0},
                                           {"x": -185, "y": 25}]})
    scenario = scenario_from_dict(data)
    polygon = scenario.world.target("p")
    assert len(polygon.geometry.exterior.coords) == 5  # 4 vertices + shapely's closure
    assert polygon.position_m == (215.0, 10.0, 0.0)
    assert scenario.world.obstacle("q").center_m == (-185.0, 8.0)


def test_load_scenario_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "round.json"
    path.write_text(json.dumps(_minimal()), encoding="utf-8")
    scenario = load_scenario(path)
    assert scenario.source == str(path) and len(scenario.vehicles) == 1


# ----------------------------------------------------------------------------- malformed

Mutation = Callable[[dict[str, Any]], None]


def _set(path: str, value: Any) -> Mutation:
    """A mutation that sets data[...][...] = value along a dotted path (ints index lists)."""
    def mutate(data: dict[str, Any]) -> None:
        keys: list[Any] = [int(k) if k.isdigit() else k for k in path.split(".")]
        node: Any = data
        for key in keys[:-1]:
            node = node[key]
        node[keys[-1]] = value
    return mutate


def _delete(path: str) -> Mutation:
    def mutate(data: dict[str, Any]) -> None:
        keys: list[Any] = [int(k) if k.isdigit() else k for k in path.split(".")]
        node: Any = data
        for key in keys[:-1]:
            node = node[key]
        del node[keys[-1]]
    return mutate


def _append(kind: str, entity: Any) -> Mutation:
    return lambda data: data.setdefault(kind, []).append(entity)


_SQUARE = [{"x": 0, "y": 0}, {"x": 10, "y": 0}, {"x": 10, "y": 10}, {"x": 0, "y": 10}]
_BOWTIE = [{"x": 0, "y": 0}, {"x": 10, "y": 10}, {"x": 10, "y": 0}, {"x": 0, "y": 10}]

MALFORMED: list[tuple[str, Mutation, str]] = [
    # session level
    ("no drones", _delete("drones"), "session: drones is required"),
    ("drones not a list", _set("drones", {"a": 1}), "session: drones must be a list"),
    ("no drone", _set("drones", []), "session: drones must list at least one"),
    ("targets not a list", _set("targets", "x"), "session: targets must be a list"),
    ("obstacles not a list", _set("obstacles", 3), "session: obstacles must be a list"),
    ("bad margin", _set("safety_margin_m", -1), "session: safety_margin_m must be >= 0"),
    ("bad name", _set("name", 5), "session: name must be a non-empty string"),
    ("origin not object", _set("origin", [47, 8]), "origin: must be a JSON object"),
    ("origin latitude", _set("origin", {"latitude_deg": 95, "longitude_deg": 8}),
     "origin: origin latitude 95"),
    ("origin longitude missing", _set("origin", {"latitude_deg": 47}),
     "origin: longitude_deg is required"),
    ("environment not object", _set("environment", [1]), "environment: must be a JSON object"),
    ("wind direction", _set("environment", {"id": "e1", "wind_direction": "up"}),
     "environment (id e1): wind_direction must be one of north"),
    ("wind speed", _set("environment", {"wind_speed": -2}),
     "environment: wind_speed must be >= 0, got -2"),
    # drones
    ("drone not object", _set("drones.0", "drone"), "drones[0]: must be a JSON object"),
    ("drone name", _delete("drones.0.name"), "drones[0] (id a1): name is required"),
    ("drone id", _set("drones.0.id", 17), "drones[0]: id must be a non-empty string, got 17"),
    ("max_speed", _set("drones.0.max_speed", -2),
     "drones[0] (id a1): max_speed must be > 0, got -2"),
    ("max_speed text", _set("drones.0.max_speed", "fast"), "max_speed must be a number"),
    ("max_speed bool", _set("drones.0.max_speed", True), "max_speed must be a number"),
    ("max_speed missing", _delete("drones.0.max_speed"), "max_speed is required"),
    ("max_altitude", _set("drones.0.max_altitude", 0), "max_altitude must be > 0, got 0"),
    ("capacity", _delete("drones.0.battery_capacity"), "battery_capacity is required"),
    ("capacity zero", _set("drones.0.battery_capacity", 0), "battery_capacity must be > 0"),
    ("perceived", _set("drones.0.perceived_radius", 0), "perceived_radius must be > 0"),
    ("task radius", _set("drones.0.task_radius", -1), "task_radius must be > 0"),
    ("heading", _set("drones.0.heading", "north"), "heading must be a number"),
    ("battery level", _set("drones.0.battery_level", "full"), "battery_level must be a number"),
    ("battery volume", _set("drones.0.battery_volume", [1]), "battery_volume must be a number"),
    ("position list", _set("drones.0.position", [1, 2, 3]),
     "position must be an object with numbers x and y"),
    ("position no y", _set("drones.0.position", {"x": 1}),
     "position must be an object with numbers x and y"),
    ("position x text", _set("drones.0.position", {"x": "1", "y": 2}),
     "position.x must be a number"),
    ("position below ground", _set("drones.0.position", {"x": 1, "y": 2, "z": -1}),
     "position.z must be between 0 and max_altitude (100), got -1"),
    ("position too high", _set("drones.0.position", {"x": 1, "y": 2, "z": 150}),
     "position.z must be between 0 and max_altitude (100), got 150"),
    ("home too high", _set("drones.0.home_position", {"x": 1, "y": 2, "z": 101}),
     "home_position.z must be between 0 and max_altitude"),
    ("drone in obstacle", _set("drones.0.position", {"x": 52, "y": 48, "z": 3}),
     "drones[0] (id a1): position (52, 48, 3) is inside obstacle 'O' (id o1)"),
    ("home in obstacle", _set("drones.0.home_position", {"x": 50, "y": 50}),
     "drones[0] (id a1): home_position (50, 50, 0) is inside obstacle 'O'"),
    ("duplicate drone id", _append("drones", {"id": "a1", "name": "Twin", "max_speed": 1,
                                              "max_altitude": 5, "battery_capacity": 5}),
     "drones[1] (id a1): id 'a1' is already used by entry [0]"),
    ("float nan", _set("drones.0.max_speed", math.nan), "max_speed must be finite"),
    # targets
    ("target type", _set("targets.0.type", "blob"), "targets[0] (id t1): type must be one of"),
    ("target type missing", _delete("targets.0.type"), "targets[0] (id t1): type is required"),
    ("target name", _delete("targets.0.name"), "targets[0] (id t1): name is required"),
    ("target position", _delete("targets.0.position"), "targets[0] (id t1): position is required"),
    ("target radius", _set("targets.0.radius", -1), "targets[0] (id t1): radius must be >= 0"),
    ("target below ground", _set("targets.0.position", {"x": 0, "y": 90, "z": -1}),
     "targets[0] (id t1): position.z must be >= 0"),
    ("target in obstacle", _set("targets.0.position", {"x": 45, "y": 45, "z": 0}),
     "targets[0] (id t1): position (45, 45, 0) is inside obstacle 'O' (id o1)"),
    ("charge amount", _append("targets", {"id": "w", "name": "W", "type": "waypoint",
                                          "charge_amount": 0, "position": {"x": 0, "y": 90}}),
     "targets[1] (id w): charge_amount must be > 0, got 0"),
    ("polygon too few", _append("targets", {"id": "p", "name": "P", "type": "polygon",
                                            "vertices": _SQUARE[:2], "position": {"x": 0, "y": 0}}),
     "targets[1] (id p): vertices must have at least 3 vertices, got 2"),
    ("polygon closing only", _append("targets", {
        "id": "p", "name": "P", "type": "polygon", "position": {"x": 0, "y": 0},
        "vertices": [*_SQUARE[:2], _SQUARE[0]]}), "vertices must have at least 3 vertices, got 2"),
    ("polygon bowtie", _append("targets", {"id": "p", "name": "P", "type": "polygon",
                                           "vertices": _BOWTIE, "position": {"x": 0, "y": 0}}),
     "targets[1] (id p): vertices must form a valid polygon"),
    ("polygon flat", _append("targets", {"id": "p", "name": "P", "type": "polygon",
                                         "vertices": [{"x": 0, "y": 0}, {"x": 1, "y": 1},
                                                      {"x": 2, "y": 2}]}),
     "targets[1] (id p): vertices must form a valid polygon"),
    ("polygon vertex", _append("targets", {"id": "p", "name": "P", "type": "polygon",
                                           "vertices": [_SQUARE[0], {"y": 3}, *_SQUARE[2:]]}),
     "targets[1] (id p): vertices[1] must be an object with numbers x and y"),
    ("polygon no vertices", _append("targets", {"id": "p", "name": "P", "type": "polygon",
                                                "position": {"x": 0, "y": 0}}),
     "targets[1] (id p): vertices is required"),
    ("polygon vertices dict", _append("targets", {"id": "p", "name": "P", "type": "polygon",
                                                  "vertices": {"x": 0}}),
     "targets[1] (id p): vertices must be a list of {x, y} points"),
    ("duplicate target id", _append("targets", {"id": "t1", "name": "T", "type": "fixed",
                                                "position": {"x": 0, "y": 90}}),
     "targets[1] (id t1): id 't1' is already used"),
    # obstacles
    ("obstacle type", _set("obstacles.0.type", "cloud"),
     "obstacles[0] (id o1): type must be one of point, circle, ellipse, polygon"),
    ("circle radius missing", _delete("obstacles.0.radius"),
     "obstacles[0] (id o1): radius is required"),
    ("circle radius zero", _set("obstacles.0.radius", 0),
     "obstacles[0] (id o1): radius must be > 0, got 0"),
    ("point radius", _append("obstacles", {"id": "p", "name": "P", "type": "point", "radius": -3,
                                           "position": {"x": 0, "y": -90}}),
     "obstacles[1] (id p): radius must be > 0, got -3"),
    ("obstacle position", _delete("obstacles.0.position"),
     "obstacles[0] (id o1): position is required"),
    ("obstacle height", _set("obstacles.0.height", -1),
     "obstacles[0] (id o1): height must be >= 0, got -1"),
    ("ellipse width", _append("obstacles", {"id": "e", "name": "E", "type": "ellipse",
                                            "width": 0, "length": 3,
                                            "position": {"x": 0, "y": -90}}),
     "obstacles[1] (id e): width must be > 0, got 0"),
    ("ellipse length", _append("obstacles", {"id": "e", "name": "E", "type": "ellipse",
                                             "width": 4, "position": {"x": 0, "y": -90}}),
     "obstacles[1] (id e): length is required"),
    ("obstacle polygon", _append("obstacles", {"id": "q", "name": "Q", "type": "polygon",
                                               "vertices": _BOWTIE}),
     "obstacles[1] (id q): vertices must form a valid polygon"),
    ("duplicate obstacle id", _append("obstacles", {"id": "o1", "name": "O2", "type": "point",
                                                    "position": {"x": 0, "y": -90}}),
     "obstacles[1] (id o1): id 'o1' is already used"),
    ("obstacle not object", _append("obstacles", None), "obstacles[1]: must be a JSON object"),
]


@pytest.mark.parametrize(("mutate", "expected"), [(m, e) for _, m, e in MALFORMED],
                         ids=[case for case, _, _ in MALFORMED])
def test_malformed_input_names_file_entity_and_field(mutate: Mutation, expected: str) -> None:
    data = copy.deepcopy(_minimal())
    mutate(data)
    with pytest.raises(ScenarioError) as caught:
        scenario_from_dict(data, source="session.json")
    message = str(caught.value)
    assert message.startswith("session.json: "), message
    assert expected in message, message


def test_malformed_files(tmp_path: Path) -> None:
    broken = tmp_path / "broken.json"
    broken.write_text("{ not json", encoding="utf-8")
    with pytest.raises(ScenarioError, match=r"broken\.json: not valid JSON"):
        load_scenario(broken)
    listed = tmp_path / "list.json"
    listed.write_text("[1, 2]", encoding="utf-8")
    with pytest.raises(ScenarioError, match=r"list\.json: the top level must be a JSON object"):
        load_scenario(listed)
    with pytest.raises(ScenarioError, match=r"missing\.json: cannot read the file"):
        load_scenario(tmp_path / "missing.json")
    with pytest.raises(ScenarioError, match=r"<dict>: session: must be a JSON object"):
        scenario_from_dict([1])  # type: ignore[arg-type]


def test_scenario_error_is_a_value_error() -> None:
    assert issubclass(ScenarioError, ValueError)


# ------------------------------------------------------------------------------- defaults


@pytest.mark.parametrize("count", [1, 7, 10, 11, 95, 250])
def test_default_scenario_grid(count: int) -> None:
    scenario = default_scenario(count)
    assert scenario.source == "defaults" and len(scenario.vehicles) == count
    assert [v.id for v in scenario.vehicles] == [f"d{k}" for k in range(1, count + 1)]
    assert [v.name for v in scenario.vehicles] == [f"Drone {k}" for k in range(1, count + 1)]
    for k, vehicle in enumerate(scenario.vehicles):
        assert vehicle.position_m == (5.0 * (k % 10), 5.0 * (k // 10), 0.0)
        assert vehicle.home_m == vehicle.position_m
        assert (vehicle.max_speed_m_s, vehicle.max_altitude_m) == (12.0, 120.0)
        assert (vehicle.perceived_radius_m, vehicle.task_radius_m) == (50.0, 20.0)
        assert (vehicle.battery_pct, vehicle.battery_capacity_mah) == (100.0, 5000.0)
    x, y, z = np.array([v.position_m for v in scenario.vehicles]).T
    assert not scenario.world.inside_obstacles(x, y, z).any()


def test_default_scenario_world() -> None:
    world = default_scenario(250).world
    kinds = sorted(t.kind for t in world.targets)
    assert kinds == ["circle", "fixed", "fixed", "fixed", "waypoint"]
    assert sorted(o.kind for o in world.obstacles) == ["circle", "ellipse", "point", "polygon"]
    assert [o.height_m for o in world.obstacles].count(15.0) == 1
    assert world.wind.speed_m_s == 0.0
    stations = [t for t in world.targets if t.is_charging_station]
    assert world.charging_station_at(*stations[0].position_m[:2]) is stations[0]
    grid = shapely.MultiPoint([(5.0 * (k % 10), 5.0 * (k // 10)) for k in range(250)])
    for geometry in [t.geometry for t in world.targets] + [o.footprint for o in world.obstacles]:
        assert shapely.distance(grid, geometry) >= 60.0
        assert shapely.distance(shapely.Point(0.0, 0.0), geometry) <= 400.0
    for target in world.targets:
        assert world.clearance_ok(*target.position_m)


def test_default_scenario_origin_and_bounds() -> None:
    origin = GeoOrigin(10.0, 20.0, 5.0)
    assert default_scenario(3, origin=origin).world.origin == origin
    for bad in (0, MAX_FLEET_VEHICLES + 1, -1):
        with pytest.raises(ValueError, match=f"between 1 and {MAX_FLEET_VEHICLES}"):
            default_scenario(bad)
    with pytest.raises(ValueError, match="integer"):
        default_scenario(2.5)  # type: ignore[arg-type]
