"""Changing a running fleet's world: obstacles and still targets replaced between physics steps,
so collision prevention, perception and charging follow at once. Moving targets keep their
motion (a world edit cannot add, remove or change one)."""

from __future__ import annotations

from emulator.flight.collision import ClearanceGuard
from emulator.flight.fleet import Fleet
from emulator.perception import Sensor
from emulator.world import World

__all__ = ["set_world"]


def set_world(fleet: Fleet, world: World) -> None:
    """Fly `fleet` in `world` from the next step on. Every vehicle's clearance is measured
    afresh (the new guard's deadlines are all now). Raises ValueError when `world`'s moving
    targets are not the fleet's."""
    moving = {t.id: t for t in fleet.world.targets if t.is_moving}
    if {t.id: t for t in world.targets if t.is_moving} != moving:
        raise ValueError("moving targets cannot be added, removed or changed while the swarm "
                         "flies")
    fleet.world = world
    fleet.sensor = Sensor(world, moving=fleet.targets)
    fleet.guard = ClearanceGuard(world, fleet.n)
    fleet._step_guard = fleet if fleet.guard.enabled else None
