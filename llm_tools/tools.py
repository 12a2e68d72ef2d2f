"""The agent-side primitives as LLM tools: one typed async function each, bound to a task's
`AgentTools`. Their signatures and docstrings are the schemas models see."""

from __future__ import annotations

from typing import Any

from benchmark.agents import AgentTools
from mavlink_gateway import Outcome

__all__ = ["TOOL_FUNCTIONS"]


def _result(outcome: Outcome) -> dict[str, Any]:
    return outcome.to_dict()


async def list_drones(tools: AgentTools) -> dict[str, Any]:
    """List your drones with their position, altitude, heading, battery and flight state."""
    return _result(tools.list_drones())


async def drone_state(tools: AgentTools, drone_id: str) -> dict[str, Any]:
    """Get one drone's current state.

    Args:
        drone_id: The drone's id, e.g. "d1".
    """
    return _result(tools.drone_state(drone_id))


async def nearby(tools: AgentTools, drone_id: str) -> dict[str, Any]:
    """What a drone's sensor perceives now: targets, obstacles and drones within its range.

    Args:
        drone_id: The drone whose sensor to read.
    """
    return _result(tools.nearby(drone_id))


async def take_off(tools: AgentTools, drone_id: str, altitude_m: float) -> dict[str, Any]:
    """Arm a drone on the ground and climb to an altitude above its home.

    Args:
        drone_id: The drone to launch.
        altitude_m: Target altitude in metres (1 to the drone's ceiling).
    """
    return _result(await tools.take_off(drone_id, altitude_m))


async def land(tools: AgentTools, drone_id: str) -> dict[str, Any]:
    """Land a flying drone where it is.

    Args:
        drone_id: The drone to land.
    """
    return _result(await tools.land(drone_id))


async def move_to(tools: AgentTools, drone_id: str, x: float, y: float, z: float
                  ) -> dict[str, Any]:
    """Fly a drone in a straight line to a point and hold there. Obstacles on the way stop
    it ("blocked"); go around them with several moves.

    Args:
        drone_id: The drone to move.
        x: East coordinate in metres.
        y: North coordinate in metres.
        z: Altitude in metres above home.
    """
    return _result(await tools.move_to(drone_id, x, y, z))


async def move_towards(tools: AgentTools, drone_id: str, heading_deg: float,
                       distance_m: float) -> dict[str, Any]:
    """Fly a drone straight along a compass heading for a distance, at its altitude.

    Args:
        drone_id: The drone to move.
        heading_deg: Compass heading in degrees (0 north, 90 east).
        distance_m: Distance in metres.
    """
    return _result(await tools.move_towards(drone_id, heading_deg, distance_m))


async def change_altitude(tools: AgentTools, drone_id: str, altitude_m: float
                          ) -> dict[str, Any]:
    """Climb or descend a flying drone to an altitude, staying above the same spot.

    Args:
        drone_id: The drone.
        altitude_m: New altitude in metres above home.
    """
    return _result(await tools.change_altitude(drone_id, altitude_m))


async def move_along_path(tools: AgentTools, drone_id: str,
                          waypoints: list[list[float]]) -> dict[str, Any]:
    """Fly a drone through waypoints in order, stopping at each.

    Args:
        drone_id: The drone.
        waypoints: Points [x, y] or [x, y, z] in metres (z: altitude; default the current).
    """
    return _result(await tools.move_along_path(drone_id, waypoints))


async def hover(tools: AgentTools, drone_id: str, duration_s: float) -> dict[str, Any]:
    """Hold a flying drone in place for a time.

    Args:
        drone_id: The drone.
        duration_s: Seconds to hover.
    """
    return _result(await tools.hover(drone_id, duration_s))


async def rotate(tools: AgentTools, drone_id: str, heading_deg: float) -> dict[str, Any]:
    """Turn a flying drone to face a compass heading.

    Args:
        drone_id: The drone.
        heading_deg: Compass heading in degrees (0 north, 90 east).
    """
    return _result(await tools.rotate(drone_id, heading_deg))


async def return_home(tools: AgentTools, drone_id: str) -> dict[str, Any]:
    """Fly a drone back to its home in a straight line and land there.

    Args:
        drone_id: The drone.
    """
    return _result(await tools.return_home(drone_id))


async def set_home(tools: AgentTools, drone_id: str) -> dict[str, Any]:
    """Make the drone's current position its home.

    Args:
        drone_id: The drone.
    """
    return _result(await tools.set_home(drone_id))


async def take_photo(tools: AgentTools, drone_id: str) -> dict[str, Any]:
    """Take a photo with the drone's camera.

    Args:
        drone_id: The drone.
    """
    return _result(await tools.take_photo(drone_id))


async def charge(tools: AgentTools, drone_id: str) -> dict[str, Any]:
    """Charge a drone that has landed on a charging station, until full.

    Args:
        drone_id: The drone.
    """
    return _result(await tools.charge(drone_id))


async def send_message(tools: AgentTools, drone_id: str, to_drone_id: str, text: str
                       ) -> dict[str, Any]:
    """Send a text message from one drone to another.

    Args:
        drone_id: The sending drone.
        to_drone_id: The receiving drone.
        text: The message.
    """
    return _result(tools.send_message(drone_id, to_drone_id, text))


async def broadcast(tools: AgentTools, drone_id: str, text: str) -> dict[str, Any]:
    """Send a text message from one drone to every other drone.

    Args:
        drone_id: The sending drone.
        text: The message.
    """
    return _result(tools.broadcast(drone_id, text))


async def read_messages(tools: AgentTools, drone_id: str) -> dict[str, Any]:
    """Read (and empty) a drone's inbox.

    Args:
        drone_id: The drone.
    """
    return _result(tools.read_messages(drone_id))


async def finish(tools: AgentTools, summary: str = "") -> dict[str, Any]:
    """Declare the task finished. Call it once, when everything asked is done.

    Args:
        summary: A short account of what was done.
    """
    return _result(tools.finish(summary))


TOOL_FUNCTIONS = (
    list_drones, drone_state, nearby, take_off, land, move_to, move_towards, change_altitude,
    move_along_path, hover, rotate, return_home, set_home, take_photo, charge, send_message,
    broadcast, read_messages, finish,
)
