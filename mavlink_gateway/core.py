"""Plumbing shared by every primitive: drone lookup, one primitive per drone at a time,
precondition checks, and waiting for an outcome within a simulated-time budget."""

from __future__ import annotations

import asyncio
import inspect
import math
import time
from collections.abc import Awaitable, Callable, Mapping
from typing import Any, Protocol

from emulator.perception import Perception
from mavlink_gateway.drone_link import DroneLink
from mavlink_gateway.outcomes import Outcome, Status

__all__ = ["GatewayCore", "Refusal", "Services"]

POLL_S = 0.01
WALL_MARGIN_S = 60.0
OBSTACLE_TEXT = "Obstacle"
FAILSAFE_TEXTS = ("Critical battery", "Emergency battery", "Offboard setpoints lost")


class Services(Protocol):
    """What the gateway needs from the swarm besides MAVLink (see emulator.services)."""

    def clock_s(self) -> float: ...
    def sense(self, drone_id: str) -> Perception: ...
    def send_message(self, sender: str, recipient: str, text: str) -> Any: ...
    def broadcast(self, sender: str, text: str) -> int: ...
    def read_messages(self, drone_id: str) -> list[Any]: ...
    def operator_land_all(self) -> None: ...
    def operator_reset_batteries(self, pct: float = 100.0) -> None: ...
    def operator_reset_to_start(self) -> None: ...


class Refusal(Exception):
    """A precondition failed: the primitive is refused and nothing is sent."""


def _number(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise Refusal(f"{name} must be a finite number, got {value!r}")
    return float(value)


class GatewayCore:
    """Drone lookup, per-drone serialisation and outcome waits."""

    def __init__(self, drones: Mapping[str, DroneLink], services: Services) -> None:
        self.drones = dict(drones)
        self.services = services
        self._busy: dict[str, str] = {}

    # --------------------------------------------------------------- lookup
    def _link(self, drone: object) -> DroneLink:
        link = self.drones.get(drone) if isinstance(drone, str) else None
        if link is None:
            ids = list(self.drones)
            known = f"{ids[0]} to {ids[-1]}" if len(ids) > 3 else ", ".join(ids)
            raise Refusal(f"unknown drone {drone!r} (known: {known})")
        return link

    async def _run(self, name: str, drone: object,
                   body: Callable[[DroneLink], Awaitable[Outcome]]) -> Outcome:
        """Run one primitive for one drone; a second one for the same drone is refused."""
        try:
            link = self._link(drone)
        except Refusal as refusal:
            return Outcome(Status.REJECTED, str(refusal))
        current = self._busy.get(link.drone_id)
        if current is not None:
            return Outcome(Status.REJECTED,
                           f"drone {link.drone_id} is busy with {current}: wait for it to end",
                           link.state())
        self._busy[link.drone_id] = name
        try:
            return await body(link)
        except Refusal as refusal:
            return Outcome(Status.REJECTED, f"{name} refused: {refusal}", link.state())
        finally:
            del self._busy[link.drone_id]

    # -------------------------------------------------------- preconditions
    @staticmethod
    def _require_air(link: DroneLink) -> None:
        if link.flight_state == "on_ground":
            raise Refusal(f"drone {link.drone_id} is on the ground: take off first")

    @staticmethod
    def _altitude(link: DroneLink, value: object, name: str = "altitude") -> float:
        altitude = _number(name, value)
        ceiling = link.profile.max_altitude_m
        if altitude > ceiling:
            raise Refusal(f"{name} {altitude:g} m exceeds this drone's ceiling of {ceiling:g} m")
        if altitude < 1.0:
            raise Refusal(f"{name} {altitude:g} m is below the 1 m minimum flight altitude")
        return altitude

    @staticmethod
    def _coordinate(name: str, value: object) -> float:
        coordinate = _number(name, value)
        if abs(coordinate) > 100_000.0:
            raise Refusal(f"{name} {coordinate:g} m is beyond the 100 km map limit")
        return coordinate

    async def _mavsdk(self, link: DroneLink, what: str, call: Awaitable[Any]) -> None:
        """Await a MAVSDK call; a refusal by the autopilot becomes a Refusal with its reason."""
        texts = len(link.status_texts)
        try:
            await call
        except Exception as error:  # MAVSDK raises one error class per plugin
            await asyncio.sleep(0.05)  # the autopilot's STATUSTEXT follows its ACK
            reason = next(iter(link.status_texts[texts:]), None)
            detail = reason or str(error)
            raise Refusal(f"the autopilot refused {what}: {detail}") from None

    # ----------------------------------------------------------------- waits
    async def _wait(self, link: DroneLink, budget_s: float, what: str,
                    done: Callable[[], Outcome | Awaitable[Outcome | None] | None], *,
                    watch_obstacles: bool = True,
                    ) -> Outcome:
        """Poll telemetry until `done` gives an outcome, an obstacle or failsafe stops the
        drone, or `budget_s` of simulated time has passed."""
        texts = len(link.status_texts)
        start_sim = self.services.clock_s()
        wall_deadline = time.monotonic() + budget_s + WALL_MARGIN_S
        while True:
            outcome = done()
            if inspect.isawaitable(outcome):
                outcome = await outcome
            if outcome is not None:
                return outcome
            new_texts = link.status_texts[texts:]
            for text in new_texts:
                if text.startswith(FAILSAFE_TEXTS):
                    return Outcome(Status.BLOCKED, f"{what} stopped: {text}", link.state())
            if watch_obstacles and any(t.startswith(OBSTACLE_TEXT) for t in new_texts) \
                    and link.speed_m_s < 0.3 and link.mode == "HOLD":
                x, y, z = link.position_m or (math.nan,) * 3
                obstacle = next(t for t in new_texts if t.startswith(OBSTACLE_TEXT))
                return Outcome(Status.BLOCKED, f"{what} stopped at ({x:.1f}, {y:.1f}, {z:.1f}): "
                               f"{obstacle.lower()}", link.state())
            elapsed = self.services.clock_s() - start_sim
            if elapsed > budget_s or time.monotonic() > wall_deadline:
                return Outcome(Status.TIMEOUT, f"{what} did not finish within {budget_s:.0f} s "
                               "of simulated time", link.state())
            await asyncio.sleep(POLL_S)

    @staticmethod
    def _arrived(link: DroneLink, target: tuple[float, float, float], tolerance_m: float
                 ) -> bool:
        pos = link.position_m
        return (pos is not None and math.dist(pos, target) <= tolerance_m
                and link.speed_m_s < 0.3 and link.mode in ("HOLD", "MISSION"))
