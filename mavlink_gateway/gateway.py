"""The gateway: every agent-side primitive of a swarm, over MAVLink (see flight, payload)."""

from __future__ import annotations

from mavlink_gateway.core import Refusal
from mavlink_gateway.drone_link import DroneProfile
from mavlink_gateway.interfaces import FleetSpec
from mavlink_gateway.outcomes import DroneState, Outcome, Status
from mavlink_gateway.payload import PayloadPrimitives

__all__ = ["Gateway", "profiles_from_scenario"]


class Gateway(PayloadPrimitives):
    """All primitives for the drones of one swarm.

    Each primitive takes a drone id and returns an Outcome. Primitives for different drones
    run concurrently; a second primitive for a drone that is still busy is refused, unless
    it replaces the current goal (`hold`, and `move_to`/`land` with `replace=True`).
    """

    async def add_drone(self, profile: DroneProfile) -> None:
        """Learn a drone that joined the swarm (discovered on the gateway's connection and
        ready with telemetry when this returns); FleetError when it does not appear."""
        if self.connection is None:
            raise RuntimeError("this gateway was given a fixed set of drones")
        self.drones.update(await self.connection.attach([profile]))

    async def remove_drone(self, drone_id: str) -> None:
        """Forget a drone that left the swarm: it is unknown from now on."""
        self.drones.pop(drone_id, None)
        self._busy.pop(drone_id, None)
        self._goals.pop(drone_id, None)
        if self.connection is not None:
            await self.connection.detach(drone_id)

    def list_drones(self) -> list[DroneState]:
        return [link.state() for link in self.drones.values()]

    def drone_state(self, drone: str) -> Outcome:
        try:
            link = self._link(drone)
        except Refusal as refusal:
            return Outcome(Status.REJECTED, str(refusal))
        state = link.state()
        return Outcome(Status.OK, state.describe(), state)


def profiles_from_scenario(scenario: FleetSpec) -> list[DroneProfile]:
    """The fleet owner's view of a scenario's drones: ids, system ids and limits."""
    return [
        DroneProfile(spec.id, spec.name, k + 1, spec.max_altitude_m, spec.max_speed_m_s,
                     spec.perceived_radius_m, spec.task_radius_m)
        for k, spec in enumerate(scenario.vehicles)
    ]
