"""The tools an agent acts with during one task, each defined once, here: its name, typed
parameters, docstring (the description every adapter shows a model) and budget accounting.

Every tool returns the gateway's `Outcome`. The OpenAI function schemas, the MCP tools, the
REST tool routes and the MultiUAV-Plat command routes are all generated from these methods
(see `tool_names` and `llm_tools.registry`). Operator resets, ground truth and the checks are
not reachable from here.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

from agent_contract.budget import BudgetedTools
from mavlink_gateway import Outcome, Status

__all__ = ["ERROR_STATUS", "RESULT_STATUSES", "AgentTools", "agent_tool", "tool_names"]

ERROR_STATUS = "error"
"""The status of a tool result that never reached the tool (unknown tool, bad arguments, a
spent budget, no task running)."""

RESULT_STATUSES: tuple[str, ...] = (*(status.value for status in Status), ERROR_STATUS)
"""Every status a tool result can carry, on every surface: the gateway's `Status` values
(what the tools return) and ERROR_STATUS. Schemas and instructions are made from this."""

F = TypeVar("F", bound=Callable[..., Any])
_MARK = "__agent_tool__"


def agent_tool(method: F) -> F:
    """Mark a method of AgentTools as a tool agents may call."""
    setattr(method, _MARK, True)
    return method


def tool_names() -> tuple[str, ...]:
    """The agent tools, in the order they are defined (and listed to models)."""
    return tuple(name for name, member in vars(AgentTools).items()
                 if getattr(member, _MARK, False))


class AgentTools(BudgetedTools):
    """One task's tool surface over a gateway. Not reusable across tasks."""

    @agent_tool
    def list_drones(self) -> Outcome:
        """List your drones with their position, altitude, heading, battery and flight
        state."""
        def call() -> Outcome:
            states = self._gw.list_drones()
            return Outcome(Status.OK, f"{len(states)} drones",
                           data={"drones": [s.to_dict() for s in states]})
        return self._sync("list_drones", call)

    @agent_tool
    def drone_state(self, drone_id: str) -> Outcome:
        """Get one drone's current state.

        Args:
            drone_id: The drone's id, e.g. "d1".
        """
        return self._sync("drone_state", lambda: self._gw.drone_state(drone_id))

    @agent_tool
    def nearby(self, drone_id: str) -> Outcome:
        """What a drone's sensor perceives now: targets, obstacles and drones within its
        range.

        Args:
            drone_id: The drone whose sensor to read.
        """
        return self._sync("nearby", lambda: self._gw.nearby(drone_id))

    @agent_tool
    async def take_off(self, drone_id: str, altitude_m: float) -> Outcome:
        """Arm a drone on the ground and climb to an altitude above its home.

        Args:
            drone_id: The drone to launch.
            altitude_m: Target altitude in metres (1 to the drone's ceiling).
        """
        return await self._call("take_off", lambda: self._gw.take_off(drone_id, altitude_m))

    @agent_tool
    async def land(self, drone_id: str) -> Outcome:
        """Land a flying drone where it is.

        Args:
            drone_id: The drone to land.
        """
        return await self._call("land", lambda: self._gw.land(drone_id))

    @agent_tool
    async def move_to(self, drone_id: str, x: float, y: float, z: float) -> Outcome:
        """Fly a drone in a straight line to a point and hold there. Obstacles on the way stop
        it ("blocked"); go around them with several moves.

        Args:
            drone_id: The drone to move.
            x: East coordinate in metres.
            y: North coordinate in metres.
            z: Altitude in metres above home.
        """
        return await self._call("move_to", lambda: self._gw.move_to(drone_id, x, y, z))

    @agent_tool
    async def move_towards(self, drone_id: str, heading_deg: float, distance_m: float,
                           dz_m: float = 0.0) -> Outcome:
        """Fly a drone straight along a compass heading for a distance, at its altitude
        (or climbing or descending by dz_m on the way).

        Args:
            drone_id: The drone to move.
            heading_deg: Compass heading in degrees (0 north, 90 east).
            distance_m: Distance in metres.
            dz_m: Altitude change in metres on the way (default 0).
        """
        return await self._call("move_towards", lambda: self._gw.move_towards(
            drone_id, heading_deg, distance_m, dz_m))

    @agent_tool
    async def change_altitude(self, drone_id: str, altitude_m: float) -> Outcome:
        """Climb or descend a flying drone to an altitude, staying above the same spot.

        Args:
            drone_id: The drone.
            altitude_m: New altitude in metres above home.
        """
        return await self._call("change_altitude",
                                lambda: self._gw.change_altitude(drone_id, altitude_m))

    @agent_tool
    async def move_along_path(self, drone_id: str, waypoints: list[list[float]]) -> Outcome:
        """Fly a drone through waypoints in order, stopping at each.

        Args:
            drone_id: The drone.
            waypoints: Points [x, y] or [x, y, z] in metres (z: altitude; default the
                current).
        """
        return await self._call("move_along_path",
                                lambda: self._gw.move_along_path(drone_id, waypoints))

    @agent_tool
    async def hover(self, drone_id: str, duration_s: float) -> Outcome:
        """Hold a flying drone in place for a time.

        Args:
            drone_id: The drone.
            duration_s: Seconds to hover.
        """
        return await self._call("hover", lambda: self._gw.hover(drone_id, duration_s))

    @agent_tool
    async def rotate(self, drone_id: str, heading_deg: float) -> Outcome:
        """Turn a flying drone to face a compass heading.

        Args:
            drone_id: The drone.
            heading_deg: Compass heading in degrees (0 north, 90 east).
        """
        return await self._call("rotate", lambda: self._gw.rotate(drone_id, heading_deg))

    @agent_tool
    async def return_home(self, drone_id: str) -> Outcome:
        """Fly a drone back to its home in a straight line and land there.

        Args:
            drone_id: The drone.
        """
        return await self._call("return_home", lambda: self._gw.return_home(drone_id))

    @agent_tool
    async def set_home(self, drone_id: str) -> Outcome:
        """Make the drone's current position its home.

        Args:
            drone_id: The drone.
        """
        return await self._call("set_home", lambda: self._gw.set_home(drone_id))

    @agent_tool
    async def take_photo(self, drone_id: str) -> Outcome:
        """Take a photo with the drone's camera.

        Args:
            drone_id: The drone.
        """
        return await self._call("take_photo", lambda: self._gw.take_photo(drone_id))

    @agent_tool
    async def charge(self, drone_id: str) -> Outcome:
        """Charge a drone that has landed on a charging station, until full.

        Args:
            drone_id: The drone.
        """
        return await self._call("charge", lambda: self._gw.charge(drone_id))

    @agent_tool
    def send_message(self, drone_id: str, to_drone_id: str, text: str) -> Outcome:
        """Send a text message from one drone to another.

        Args:
            drone_id: The sending drone.
            to_drone_id: The receiving drone.
            text: The message.
        """
        return self._sync("send_message",
                          lambda: self._gw.send_message(drone_id, to_drone_id, text))

    @agent_tool
    def broadcast(self, drone_id: str, text: str) -> Outcome:
        """Send a text message from one drone to every other drone.

        Args:
            drone_id: The sending drone.
            text: The message.
        """
        return self._sync("broadcast", lambda: self._gw.broadcast(drone_id, text))

    @agent_tool
    def read_messages(self, drone_id: str) -> Outcome:
        """Read (and empty) a drone's inbox.

        Args:
            drone_id: The drone.
        """
        return self._sync("read_messages", lambda: self._gw.read_messages(drone_id))

    @agent_tool
    async def wait(self, drone_id: str, duration_s: float) -> Outcome:
        """Let simulated time pass (every drone keeps doing what it does) until a message for
        this drone arrives or duration_s has passed, whichever comes first.

        Args:
            drone_id: The drone whose messages end the wait.
            duration_s: The longest wait, in seconds.
        """
        return await self._call("wait", lambda: self._gw.wait(drone_id, duration_s))

    @agent_tool
    def finish(self, summary: str = "") -> Outcome:
        """Declare the task finished. Call it once, when everything asked is done. Scoring
        happens afterwards, out of the agent's sight.

        Args:
            summary: A short account of what was done.
        """
        if self.finished:
            return Outcome(Status.REJECTED, "the task is already finished")
        self.finished = True
        self.summary = str(summary)[:2000]
        return Outcome(Status.OK, "task finished")
