"""Any valid MultiUAV-Plat session file loads and starts a swarm: files drawn over every entity
type, optional field and value range that `../shared/spec/entities.md` allows (worlds with and
without tasks, drones on the ground and in the air, every target and obstacle kind, moving
targets in velocity and path mode, limits far outside PX4's parameter ranges). A value our
physics reads differently is mapped with a note, never refused."""

from __future__ import annotations

import json
import random
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from benchmark.authoring.importer import import_session
from emulator.clock import ClockConfig
from emulator.flight.params import ParamStore
from emulator.scenario import scenario_from_dict
from emulator.swarm import PortPlan, Swarm

FILES = settings(derandomize=True, database=None, deadline=None, max_examples=60)
WIND_DIRECTIONS = ("north", "northeast", "east", "southeast", "south", "southwest", "west",
                   "northwest")
LIMIT_PARAMS = {"max_speed_m_s": "MPC_XY_VEL_MAX", "max_altitude_m": "GF_MAX_VER_DIST",
                "perceived_radius_m": "SIM_SENS_RAD", "task_radius_m": "SIM_TASK_RAD"}


def _hex(rng: random.Random) -> str:
    return f"{rng.getrandbits(32):08x}"


def _drone(rng: random.Random, k: int) -> dict[str, Any]:
    max_altitude = rng.choice([0.5, 5.0, 50.0, 120.0, 300.0, 20_000.0])
    drone: dict[str, Any] = {
        "id": _hex(rng), "name": f"Drone {k + 1}", "model": rng.choice(["Quad-X", "M300"]),
        "position": {"x": rng.uniform(-50.0, 1500.0), "y": rng.uniform(-50.0, 1500.0)},
        "max_speed": rng.choice([0.1, 1.0, 15.0, 40.0, 100.0]),
        "max_altitude": max_altitude,
        "battery_capacity": rng.choice([0.5, 60.0, 74.0, 100.0, 5000.0, 200_000.0])}
    optional: dict[str, Any] = {
        "perceived_radius": rng.choice([0.5, 10.0, 120.0, 20_000.0]),
        "task_radius": rng.choice([0.05, 1.0, 20.0, 20_000.0]),
        "battery_level": rng.choice([0.0, 0.2, 3.0, 50.0, 150.0]),
        "battery_volume": rng.uniform(0.0, 100.0),
        "status": rng.choice(["idle", "ready", "hovering", "flying", "offline", "emergency"]),
        "heading": rng.uniform(-720.0, 720.0), "speed": 3.0, "created_at": 1.7e9,
        "home_position": {"x": drone["position"]["x"], "y": drone["position"]["y"], "z": 0.0}}
    drone.update({key: value for key, value in optional.items() if rng.random() < 0.4})
    if rng.random() < 0.3:
        drone["position"]["z"] = rng.uniform(0.0, min(max_altitude, 50.0))
    return drone


def _target(rng: random.Random, k: int) -> dict[str, Any]:
    kind = rng.choice(["fixed", "moving", "waypoint", "circle", "polygon"])
    x, y = rng.uniform(2000.0, 2400.0), rng.uniform(2000.0, 2400.0)
    target: dict[str, Any] = {"id": _hex(rng), "name": f"{kind.title()} Target {k + 1}",
                              "type": kind, "position": {"x": x, "y": y, "z": 0.0}}
    if kind == "polygon":
        target["vertices"] = [{"x": x, "y": y}, {"x": x + 30.0, "y": y},
                              {"x": x + 30.0, "y": y + 20.0}]
        if rng.random() < 0.5:
            target["vertices"].append(dict(target["vertices"][0]))  # a closed ring
    elif rng.random() < 0.7:
        target["radius"] = rng.choice([0.0, 1.0, 10.0, 50.0])
    if kind == "moving":
        if rng.random() < 0.5:
            target["velocity"] = {"x": 1.0, "y": 0.5, "z": 0.0}
        else:
            target["moving_path"] = [{"x": x, "y": y}, {"x": x + 80.0, "y": y + 40.0}]
        if rng.random() < 0.5:
            target["moving_duration"] = rng.choice([5.0, 10.0, 60.0])
    if kind == "waypoint" and rng.random() < 0.5:
        target["charge_amount"] = rng.choice([5.0, 25.0, 100.0])
    if rng.random() < 0.2:
        target["description"] = "seen from the road"
    return target


def _obstacle(rng: random.Random, k: int) -> dict[str, Any]:
    kind = rng.choice(["point", "circle", "ellipse", "polygon"])
    x, y = rng.uniform(3000.0, 3400.0), rng.uniform(3000.0, 3400.0)
    obstacle: dict[str, Any] = {"id": _hex(rng), "name": f"Obstacle {k + 1}", "type": kind,
                                "position": {"x": x, "y": y, "z": 0.0}}
    if kind == "circle" or (kind == "point" and rng.random() < 0.5):
        obstacle["radius"] = rng.choice([0.5, 5.0, 30.0])
    if kind == "ellipse":
        obstacle["width"], obstacle["length"] = 10.0, 20.0
    if kind == "polygon":
        obstacle["vertices"] = [{"x": x, "y": y}, {"x": x + 30.0, "y": y},
                                {"x": x + 30.0, "y": y + 20.0}, {"x": x, "y": y + 20.0}]
    if rng.random() < 0.7:
        obstacle["height"] = rng.choice([0.0, 5.0, 40.0])
    return obstacle


def reference_file(seed: int) -> dict[str, Any]:
    """One valid MultiUAV-Plat session, drawn from `seed`."""
    rng = random.Random(seed)
    data: dict[str, Any] = {
        "id": _hex(rng), "name": "Drawn Session",
        "drones": [_drone(rng, k) for k in range(rng.randint(1, 8))],
        "targets": [_target(rng, k) for k in range(rng.randint(0, 6))],
        "obstacles": [_obstacle(rng, k) for k in range(rng.randint(0, 5))]}
    optional: dict[str, Any] = {
        "environment": {"name": "Env", "weather": rng.choice(["clear", "rain", "storm"]),
                        "wind_speed": rng.choice([0.0, 3.0, 20.0]),
                        "wind_direction": rng.choice(WIND_DIRECTIONS)},
        "task_type": rng.choice(["area_search", "target_tracking", "others", "unheard_of"]),
        "is_distance_3d": True, "canvas_width": 1024, "canvas_height": 768, "tasks": [],
        "status": "inactive", "history": {}}
    data.update({key: value for key, value in optional.items() if rng.random() < 0.5})
    return data


async def _starts(data: dict[str, Any]) -> None:
    scenario = scenario_from_dict(data, source="drawn.json")
    for spec in scenario.vehicles:
        for field, param in LIMIT_PARAMS.items():
            definition = ParamStore.definition(param)
            assert definition.minimum <= getattr(spec, field) <= definition.maximum
    notes = "\n".join(scenario.notes)
    for k, drone in enumerate(data["drones"]):
        if drone["max_speed"] > 30.0:
            assert f"drones[{k}] (id {drone['id']}).max_speed {drone['max_speed']:g}" in notes
    session, _ = import_session(json.loads(json.dumps(data)), source="drawn.json")
    assert len(session["drones"]) == len(data["drones"])
    ports = PortPlan(bind_host="127.0.0.1", bind_port=0, api_port=0, gcs_port=0)
    async with Swarm(scenario, clock=ClockConfig(stepped=True), ports=ports) as swarm:
        assert swarm.n == len(data["drones"])


@FILES
@given(st.integers(min_value=0, max_value=2**32 - 1))
async def test_every_valid_reference_file_loads_and_starts(seed: int) -> None:
    await _starts(reference_file(seed))


async def test_limits_outside_the_parameter_ranges_are_flown_at_the_nearest_end() -> None:
    data = reference_file(1)
    data["drones"] = [{**data["drones"][0], "max_speed": 45.0, "max_altitude": 0.5,
                       "perceived_radius": 50_000.0, "task_radius": 0.01,
                       "position": {"x": 10.0, "y": 10.0, "z": 0.0}}]
    scenario = scenario_from_dict(data, source="drawn.json")
    (spec,) = scenario.vehicles
    assert (spec.max_speed_m_s, spec.max_altitude_m) == (30.0, 1.0)
    assert (spec.perceived_radius_m, spec.task_radius_m) == (10_000.0, 0.1)
    notes = "\n".join(scenario.notes)
    assert "max_speed 45 is outside MPC_XY_VEL_MAX's range [0.5, 30]; flown as 30" in notes
    assert "perceived_radius 50000 is outside SIM_SENS_RAD's range" in notes
    await _starts(data)
