"""Offboard control of one autopilot: position and velocity set-points from a companion.

PX4's rules: entering OFFBOARD needs a set-point received within COM_OF_LOSS_T, and when
set-points stop arriving for that long the vehicle holds. Both are wall-clock rules, since
they concern the link rather than the flight.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from emulator.flight import dynamics as dy
from emulator.flight.modes import FlightMode, LandedState
from emulator.flight.refusal import CommandRefused, Severity

if TYPE_CHECKING:
    from emulator.flight.autopilot import Autopilot

__all__ = ["OffboardControl"]

Vec3 = tuple[float, float, float]


class OffboardControl:
    """The latest set-point of one vehicle and whether it is being flown."""

    def __init__(self, autopilot: Autopilot) -> None:
        self.ap = autopilot
        self._setpoint: tuple[str, Vec3, float] | None = None
        self._received_wall_s = -math.inf
        self._applied: tuple[str, Vec3, float] | None = None

    def setpoint(self, kind: str, vector: Vec3, yaw_deg: float, wall_now_s: float) -> None:
        """A position ('position', ENU m) or velocity ('velocity', ENU m/s) set-point."""
        self._setpoint = (kind, vector, yaw_deg)
        self._received_wall_s = wall_now_s
        if self.ap.mode is FlightMode.OFFBOARD and self._setpoint != self._applied:
            self.apply()

    def enter(self, wall_now_s: float) -> None:
        ap = self.ap
        if wall_now_s - self._received_wall_s > ap.params["COM_OF_LOSS_T"]:
            raise CommandRefused("Offboard refused: no recent setpoint")
        ap.mission.pause()
        ap._set_mode(FlightMode.OFFBOARD)
        self.apply()

    def apply(self) -> None:
        ap = self.ap
        sp = self._setpoint
        if sp is None or not ap.armed:
            return
        self._applied = sp
        kind, vec, yaw = sp
        dyn, k = ap.fleet.dyn, ap.k
        rising = vec[2] > 0.5 if kind == "position" else vec[2] > 0.1
        if not ap.in_air:
            if not rising:
                return
            ap.fleet.airborne[k] = True
            ap.landed_state = LandedState.IN_AIR
            ap._cancel_timer()
            ap._update_charging()
            ap._event("takeoff", altitude_m=vec[2] if kind == "position" else None)
        if kind == "position":
            ap.fly_to((vec[0], vec[1], max(vec[2], 0.0)), tracking=dy.TRACK_SETTLE, yaw_deg=yaw)
        else:
            ap._on_arrive = None
            ap._blockage = None
            dyn.control[k] = dy.CONTROL_VELOCITY
            dyn.velocity_sp_m_s[k] = vec
            dyn.tracking[k] = dy.TRACK_NONE
            dyn.goal_yaw_deg[k] = yaw
            ap._goal_pending = False
            ap._refresh_busy()

    def check_link(self, wall_now_s: float) -> None:
        """Offboard failsafe: hold when set-points stop arriving (wall-clock timeout)."""
        ap = self.ap
        if ap.mode is FlightMode.OFFBOARD and (
            wall_now_s - self._received_wall_s > ap.params["COM_OF_LOSS_T"]
        ):
            ap._event("failsafe", reason="offboard_lost")
            ap._say(Severity.WARNING, "Offboard setpoints lost: holding")
            self._applied = None
            ap.hold()
