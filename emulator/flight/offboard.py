"""Offboard control of one autopilot: position and velocity set-points from a companion.

PX4's rules: entering OFFBOARD needs a set-point received within COM_OF_LOSS_T, and when
set-points stop arriving for that long the vehicle holds. Both are wall-clock rules, since
they concern the link rather than the flight. The geofence applies as in every other mode:
a position set-point outside it is refused, and a vehicle flown out of it by velocity
set-points holds at the fence.
"""

from __future__ import annotations

import math

from emulator.flight import dynamics as dy
from emulator.flight.limits import check_target
from emulator.flight.modes import FlightMode, LandedState
from emulator.flight.refusal import CommandRefused, Severity
from emulator.flight.vehicle_control import VehicleControl

__all__ = ["OffboardControl"]

Vec3 = tuple[float, float, float]


class OffboardControl:
    """The latest set-point of one vehicle and whether it is being flown."""

    def __init__(self, autopilot: VehicleControl) -> None:
        self.ap = autopilot
        self._setpoint: tuple[str, Vec3, float] | None = None
        self._received_wall_s = -math.inf
        self._applied: tuple[str, Vec3, float] | None = None

    def setpoint(self, kind: str, vector: Vec3, yaw_deg: float, wall_now_s: float) -> None:
        """A position ('position', ENU m; below ground means on it) or velocity ('velocity',
        ENU m/s) set-point. Raises CommandRefused for a position outside the geofence."""
        if kind == "position":
            vector = (vector[0], vector[1], max(vector[2], 0.0))
            check_target(self.ap.params, self.ap.state.home_m, vector, "Offboard set-point")
        self._setpoint = (kind, vector, yaw_deg)
        self._received_wall_s = wall_now_s
        if self.ap.state.mode is FlightMode.OFFBOARD and self._setpoint != self._applied:
            self.apply()

    def enter(self, wall_now_s: float) -> None:
        ap = self.ap
        if wall_now_s - self._received_wall_s > ap.params["COM_OF_LOSS_T"]:
            raise CommandRefused("Offboard refused: no recent setpoint")
        ap.pause_mission()
        ap.switch_mode(FlightMode.OFFBOARD)
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
            ap.state.landed_state = LandedState.IN_AIR
            ap.cancel_timer()
            ap.update_charging()
            ap.event("takeoff", altitude_m=vec[2] if kind == "position" else None)
        if kind == "position":
            ap.fly_to(vec, tracking=dy.TRACK_SETTLE, yaw_deg=yaw)
        else:
            ap.drop_goal()
            dyn.control[k] = dy.CONTROL_VELOCITY
            dyn.velocity_sp_m_s[k] = vec
            dyn.tracking[k] = dy.TRACK_NONE
            dyn.goal_yaw_deg[k] = yaw
            ap.refresh_busy()

    def check_fence(self) -> None:
        """Geofence for velocity set-points: hold once beyond the ceiling or the fence radius
        and still moving outwards (called every physics step while flying by velocity)."""
        ap = self.ap
        p, k = ap.params, ap.k
        x, y, z = ap.position_m
        hx, hy, hz = ap.state.home_m
        vx, vy, vz = (float(v) for v in ap.fleet.dyn.velocity_sp_m_s[k])
        above = z - hz > p["GF_MAX_VER_DIST"] and vz > 0.0
        outside = math.hypot(x - hx, y - hy) > p["GF_MAX_HOR_DIST"] and (
            (x - hx) * vx + (y - hy) * vy > 0.0
        )
        if above or outside:
            ap.event("failsafe", reason="geofence")
            ap.say(Severity.WARNING, "Geofence reached: holding")
            self._applied = None
            ap.hold()

    def check_link(self, wall_now_s: float) -> None:
        """Offboard failsafe: hold when set-points stop arriving (wall-clock timeout)."""
        ap = self.ap
        if ap.state.mode is FlightMode.OFFBOARD and (
            wall_now_s - self._received_wall_s > ap.params["COM_OF_LOSS_T"]
        ):
            ap.event("failsafe", reason="offboard_lost")
            ap.say(Severity.WARNING, "Offboard setpoints lost: holding")
            self._applied = None
            ap.hold()
