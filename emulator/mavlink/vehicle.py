"""What a command handler may use of a vehicle: its autopilot, camera, gimbal and streams.

A structural type (the vehicle link satisfies it), so handlers depend on this and not on the
link that calls them.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

from emulator.flight.autopilot import Autopilot
from emulator.mavlink.camera import CameraComponent
from emulator.mavlink.gimbal import GimbalComponent

__all__ = ["Vehicle"]


class Vehicle(Protocol):
    ap: Autopilot
    camera: CameraComponent
    gimbal: GimbalComponent | None  # where the session asks for one
    command_peer: tuple[int, int]  # (system, component) that sent the command
    wall_now_s: float  # the wall clock when the command arrived
    # told when the vehicle's MAVLink goes off or comes back (the swarm's link faults)
    on_mavlink_signal: Callable[[Autopilot], None] | None

    def set_stream_interval(self, msg_id: int, interval_s: float | None) -> bool:
        """Change one of the vehicle's stream periods (None: default, inf: off)."""
        ...

    def can_send_once(self, msg_id: int) -> bool:
        """Whether the vehicle can send message `msg_id` on request."""
        ...
