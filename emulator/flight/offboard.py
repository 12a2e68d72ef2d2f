"""Offboard control of one autopilot: position and velocity set-points from a companion.

PX4's rules: entering OFFBOARD needs a set-point received within COM_OF_LOSS_T, and when
set-points stop arriving for that long the vehicle holds. Both are wall-clock rules, since
they concern the link rather than the flight. The geofence applies as in every other mode:
a position set-point outside it is refused, and a vehicle flown out of it by velocity
set-points holds at the fence.

A velocity set-point may carry a yaw rate (followed every physics step, within
MC_YAWRATE_MAX) and may be given in the body frame (forward, right, up): it is turned with
the heading every physics step, so a forward speed with a yaw rate flies a circle. A position
set-point on the ground flown to from the air is a landing: the vehicle descends until its
touchdown is detected and disarms after COM_DISARM_LAND, as PX4's land detector does.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from emulator.flight import dynamics as dy
from emulator.flight.attitude_control import attitude_acceleration_enu
from emulator.flight.limits import check_target
from emulator.flight.modes import FlightMode
from emulator.flight.offboard_frames import body_to_enu
from emulator.flight.refusal import CommandRefused
from emulator.flight.vehicle_control import VehicleControl
from emulator.truth_events import TruthEventKind
from mavlink_vocabulary import GeofenceReached, OffboardLost

__all__ = ["OffboardControl", "Setpoint"]

Vec3 = tuple[float, float, float]
GROUND_SETPOINT_M = 0.0  # a position set-point this high (or lower) is on the ground


class Setpoint(NamedTuple):
    kind: str  # "position" (ENU m), "velocity" (ENU m/s, or body forward/right/up m/s) or
    # "attitude" (roll deg, pitch deg, normalised thrust)
    vector: Vec3
    yaw_deg: float  # NaN: none
    yaw_rate_deg_s: float = math.nan  # NaN: none; positive turns clockwise seen from above
    body: bool = False  # a velocity in the body frame: (forward, right, up)


class OffboardControl:
    """The latest set-point of one vehicle and whether it is being flown."""

    def __init__(self, autopilot: VehicleControl) -> None:
        self.ap = autopilot
        self._setpoint: Setpoint | None = None
        self._received_wall_s = -math.inf
        self._applied: Setpoint | None = None

    def setpoint(self, kind: str, vector: Vec3, yaw_deg: float, wall_now_s: float, *,
                 yaw_rate_deg_s: float = math.nan, body: bool = False) -> None:
        """A position ('position', ENU m; below ground means on it) or velocity ('velocity',
        ENU m/s, or body forward/right/up m/s with body=True) set-point; a yaw rate applies
        when no yaw is given. Raises CommandRefused for a position outside the geofence."""
        if kind == "position":
            vector = (vector[0], vector[1], max(vector[2], 0.0))
            check_target(self.ap.params, self.ap.state.home_m, vector, "Offboard set-point")
            body = False
        if math.isfinite(yaw_deg) or kind == "position":
            yaw_rate_deg_s = math.nan
        self._setpoint = Setpoint(kind, vector, yaw_deg, yaw_rate_deg_s, body)
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

    def _velocity_enu(self, sp: Setpoint) -> Vec3:
        if not sp.body:
            return sp.vector
        forward, right, up = sp.vector
        east, north = body_to_enu(float(self.ap.fleet.dyn.yaw_deg[self.ap.k]), forward, right)
        return east, north, up

    def apply(self) -> None:
        ap = self.ap
        sp = self._setpoint
        if sp is None or not ap.armed:
            return
        self._applied = sp
        dyn, k = ap.fleet.dyn, ap.k
        vec = sp.vector
        if sp.kind == "attitude":
            rising = vec[2] > ap.params["MPC_THR_HOVER"]
        else:
            rising = vec[2] > 0.5 if sp.kind == "position" else vec[2] > 0.1
        if not ap.in_air:
            if not rising:
                return
            ap.lift_off(vec[2] if sp.kind == "position" else None)
        if sp.kind == "position":
            if vec[2] <= GROUND_SETPOINT_M:  # on the ground: go there and descend to touchdown
                ap.descend_and_land((vec[0], vec[1]))
            else:
                ap.fly_to(vec, tracking=dy.TRACK_SETTLE, yaw_deg=sp.yaw_deg)
            return
        ap.drop_goal()
        dyn.control[k] = dy.CONTROL_VELOCITY
        if sp.kind == "attitude":  # from the velocity it has, changed by the attitude's
            dyn.velocity_sp_m_s[k] = dyn.velocity_m_s[k]
        else:
            dyn.velocity_sp_m_s[k] = self._velocity_enu(sp)
        dyn.tracking[k] = dy.TRACK_NONE
        dyn.goal_yaw_deg[k] = sp.yaw_deg
        ap.refresh_busy()

    def on_step(self, dt_s: float) -> None:
        """Every physics step while flying by velocity: the yaw rate, the body frame turned
        with the heading, then the geofence."""
        sp = self._applied
        if sp is not None and sp.kind != "position":
            dyn, k = self.ap.fleet.dyn, self.ap.k
            if math.isfinite(sp.yaw_rate_deg_s):
                limit = self.ap.params["MC_YAWRATE_MAX"]
                rate = min(max(sp.yaw_rate_deg_s, -limit), limit)
                dyn.yaw_rate_deg_s[k] = max(abs(rate), self.ap.params["MPC_YAWRAUTO_MAX"])
                dyn.goal_yaw_deg[k] = (float(dyn.yaw_deg[k]) + rate * dt_s) % 360.0
            if sp.kind == "attitude":
                self._fly_attitude(sp, dt_s)
            elif sp.body:
                dyn.velocity_sp_m_s[k] = self._velocity_enu(sp)
        self.check_fence()

    def _fly_attitude(self, sp: Setpoint, dt_s: float) -> None:
        ap = self.ap
        dyn, k, p = ap.fleet.dyn, ap.k, ap.params
        roll_deg, pitch_deg, thrust = sp.vector
        yaw_deg = sp.yaw_deg if math.isfinite(sp.yaw_deg) else float(dyn.yaw_deg[k])
        a = attitude_acceleration_enu(roll_deg, pitch_deg, yaw_deg, thrust, p["MPC_THR_HOVER"])
        vx, vy, vz = (float(v) + ai * dt_s for v, ai in zip(dyn.velocity_sp_m_s[k], a,
                                                              strict=True))
        limit = p["MPC_XY_VEL_MAX"]
        speed = math.hypot(vx, vy)
        if speed > limit:
            vx, vy = vx * limit / speed, vy * limit / speed
        vz = min(max(vz, -p["MPC_Z_VEL_MAX_DN"]), p["MPC_Z_VEL_MAX_UP"])
        dyn.velocity_sp_m_s[k] = (vx, vy, vz)

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
            ap.event(TruthEventKind.FAILSAFE, reason="geofence")
            ap.announce(GeofenceReached())
            self._stop()
            ap.hold()

    def _stop(self) -> None:
        """The set-point is no longer flown: the yaw rate limit returns to its parameter."""
        self._applied = None
        self.ap.fleet.dyn.yaw_rate_deg_s[self.ap.k] = self.ap.params["MPC_YAWRAUTO_MAX"]

    def check_link(self, wall_now_s: float) -> None:
        """Offboard failsafe: hold when set-points stop arriving (wall-clock timeout)."""
        ap = self.ap
        if ap.state.mode is FlightMode.OFFBOARD and (
            wall_now_s - self._received_wall_s > ap.params["COM_OF_LOSS_T"]
        ):
            ap.event(TruthEventKind.FAILSAFE, reason="offboard_lost")
            ap.announce(OffboardLost())
            self._stop()
            ap.hold()
