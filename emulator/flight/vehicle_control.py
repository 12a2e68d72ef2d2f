"""What the autopilot offers its parts: the mission runner, the take-off, landing and RTL
sequences, failures and offboard control drive one vehicle through this protocol.

emulator.flight.autopilot.Autopilot is the one implementation. The parts name this protocol
rather than the autopilot, which imports them, so that no import circle forms.
"""

from __future__ import annotations

from typing import Protocol

from emulator.flight.camera import CameraCarrier, ImageCapture
from emulator.flight.listener import AutopilotListener
from emulator.flight.modes import FlightMode
from emulator.flight.vehicle_state import Phase, TimerAction, VehicleState
from emulator.truth_events import TruthEventKind
from mavlink_vocabulary import Announcement

__all__ = ["VehicleControl"]

Vec3 = tuple[float, float, float]


class VehicleControl(CameraCarrier, Protocol):
    """One vehicle's autopilot as its parts see it (a camera carrier among other things)."""

    @property
    def state(self) -> VehicleState: ...
    @property
    def listener(self) -> AutopilotListener: ...
    @property
    def armed(self) -> bool: ...
    @property
    def in_air(self) -> bool: ...
    @property
    def battery_pct(self) -> float: ...

    # ------------------------------------------------------------ bookkeeping
    def event(self, kind: TruthEventKind, **data: object) -> None:
        """Record a ground-truth event of this vehicle."""

    def say(self, severity: int, text: str) -> None:
        """Announce a STATUSTEXT."""

    def announce(self, message: Announcement) -> None:
        """Send one of the vocabulary's STATUSTEXT messages, with its severity."""

    def switch_mode(self, mode: FlightMode) -> None:
        """Enter `mode` (recorded and announced); nothing else changes."""

    def pause_mission(self) -> None: ...
    def rtl_destination_m(self) -> Vec3:
        """Where RTL goes: home or the closest rally point."""
    def set_timer(self, delay_s: float, action: TimerAction, *, busy: bool,
                  seq: int = ...) -> None: ...
    def cancel_timer(self) -> None: ...
    def refresh_busy(self) -> None: ...
    def update_charging(self) -> None: ...

    # ------------------------------------------------------------------ goals
    def drop_goal(self) -> None:
        """Forget the current goal's sequence step, blockage and pending end."""

    def fly_to(
        self, target_m: Vec3, *, phase: Phase = ..., tracking: int = ...,
        speed_m_s: float | None = ..., climb_m_s: float | None = ...,
        descent_m_s: float | None = ..., yaw_deg: float = ...,
    ) -> None: ...
    def lift_off(self, altitude_m: float | None) -> None: ...
    def brake_and_hold(self) -> None: ...
    def hold(self) -> None: ...
    def disarm(self, *, force: bool = ...) -> None: ...
    def begin_climb(self, target_m: Vec3, phase: Phase) -> None: ...
    def descend_and_land(self, at_m: tuple[float, float] | None) -> None: ...
    def start_land(self, at_m: tuple[float, float] | None) -> None: ...
    def start_rtl(self) -> None: ...
    def set_yaw(self, heading_deg: float, *, rate_deg_s: float = ..., relative: bool = ...,
                direction: int = ...) -> None: ...
    def change_speed(self, kind: float, speed_m_s: float) -> None: ...
    def take_photo(self) -> ImageCapture: ...
    def on_battery_level(self, level: int) -> None: ...
