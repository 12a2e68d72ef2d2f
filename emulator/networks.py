"""How a fleet's vehicles are split into MAVLink networks and which system id each one has.

MAVLink system ids are 1-255 per network (0 is broadcast; 251-255 are left to ground stations
and tools), so one network carries at most 250 vehicles. A fleet of more runs as several
networks side by side, each on its own socket: vehicle k is in network k // 250 with system id
k % 250 + 1, so a fleet of up to 250 keeps system id k + 1.
"""

from __future__ import annotations

import math

__all__ = ["MAX_FLEET_VEHICLES", "VEHICLES_PER_NETWORK", "network_count", "network_of",
           "system_id"]

VEHICLES_PER_NETWORK = 250
MAX_FLEET_VEHICLES = 80 * VEHICLES_PER_NETWORK  # one process: 20,000 vehicles in 80 networks


def system_id(k: int) -> int:
    """The MAVLink system id of vehicle k (index in its fleet)."""
    return k % VEHICLES_PER_NETWORK + 1


def network_of(k: int) -> int:
    """The network (0, 1, ...) that vehicle k belongs to."""
    return k // VEHICLES_PER_NETWORK


def network_count(vehicles: int) -> int:
    """The networks a fleet of `vehicles` needs."""
    return max(1, math.ceil(vehicles / VEHICLES_PER_NETWORK))
