"""The one tiny-scenario builder of the test suite: drones by number, and a scenario around
them with whatever obstacles, targets and wind a test needs."""

from __future__ import annotations

from collections.abc import Sequence

from emulator.scenario import Scenario, VehicleSpec
from emulator.world import CALM, Obstacle, Target, Wind, World

__all__ = ["tiny_scenario", "vehicle"]


def vehicle(k: int, x: float = 0.0, y: float = 0.0, z: float = 0.0, *,
            battery_pct: float = 100.0, perceived_radius_m: float = 50.0,
            task_radius_m: float = 20.0, heading_deg: float = 0.0) -> VehicleSpec:
    """Drone d<k> at (x, y, z), home on the ground below it."""
    return VehicleSpec(
        id=f"d{k}", name=f"Drone {k}", model="test", position_m=(x, y, z),
        heading_deg=heading_deg, home_m=(x, y, 0.0), max_speed_m_s=12.0, max_altitude_m=120.0,
        perceived_radius_m=perceived_radius_m, task_radius_m=task_radius_m,
        battery_pct=battery_pct, battery_capacity_mah=5000.0)


def tiny_scenario(vehicles: Sequence[VehicleSpec], *, obstacles: Sequence[Obstacle] = (),
                  targets: Sequence[Target] = (), wind: Wind = CALM,
                  task_type: str = "others", name: str = "test") -> Scenario:
    """A scenario of `vehicles` in a world of the given obstacles, targets and wind."""
    world = World(obstacles=obstacles, targets=targets, wind=wind)
    return Scenario(name, task_type, world, tuple(vehicles), "tests")
