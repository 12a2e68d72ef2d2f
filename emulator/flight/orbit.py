"""Orbit mode (PX4's MAV_CMD_DO_ORBIT): circle a point at a radius, speed and yaw behaviour.

The vehicle is flown by velocity every physics step: the tangential speed along the circle
(clockwise seen from above for a positive radius, as PX4), a radial correction that brings it
onto the circle (from anywhere: it spirals in or out) and a vertical one that holds the orbit
altitude. Like PX4 the speed is bounded by the centripetal acceleration MPC_ACC_HOR allows at
that radius, the radius by MC_ORBIT_RAD_MAX. PX4 reports the mode as POSCTL/ORBIT and orbits
until another mode is chosen (the command's number of orbits is not supported by PX4 either).
"""

from __future__ import annotations

import math
from enum import IntEnum

from emulator.flight import dynamics as dy
from emulator.flight.limits import check_target
from emulator.flight.modes import FlightMode
from emulator.flight.refusal import CommandRefused
from emulator.flight.vehicle_control import VehicleControl
from emulator.truth_events import TruthEventKind

__all__ = ["ORBIT_MIN_RADIUS_M", "OrbitControl", "OrbitYaw"]

ORBIT_MIN_RADIUS_M = 1.0
DEFAULT_RADIUS_M = 10.0  # the orbit radius when the command gives none
DEFAULT_SPEED_M_S = 1.0  # PX4's orbit speed when the command gives none
RADIAL_GAIN_1_S = 1.0  # radial speed per metre off the circle
VERTICAL_GAIN_1_S = 1.0


class OrbitYaw(IntEnum):
    """ORBIT_YAW_BEHAVIOUR (MAV_CMD_DO_ORBIT param3)."""

    HOLD_FRONT_TO_CIRCLE_CENTER = 0
    HOLD_INITIAL_HEADING = 1
    UNCONTROLLED = 2
    HOLD_FRONT_TANGENT_TO_CIRCLE = 3
    RC_CONTROLLED = 4  # no RC here: the initial heading is held


def _bearing_deg(east: float, north: float) -> float:
    return math.degrees(math.atan2(east, north)) % 360.0


class OrbitControl:
    """The orbit one vehicle flies: centre (ENU m), radius, speed and yaw behaviour."""

    def __init__(self, autopilot: VehicleControl) -> None:
        self.ap = autopilot
        self.center_m: tuple[float, float, float] | None = None
        self.radius_m = 0.0  # signed: positive clockwise
        self.speed_m_s = DEFAULT_SPEED_M_S
        self.yaw = OrbitYaw.HOLD_FRONT_TO_CIRCLE_CENTER
        self._initial_yaw_deg = 0.0

    @property
    def active(self) -> bool:
        return self.ap.state.mode is FlightMode.ORBIT

    def start(self, center_m: tuple[float | None, float | None, float | None],
              radius_m: float, speed_m_s: float, yaw: float) -> None:
        """Orbit a centre (None parts: the current centre when orbiting, else where the
        vehicle is); NaN radius, speed or yaw: the current orbit's, else the defaults.
        Raises CommandRefused before anything changes."""
        ap, p = self.ap, self.ap.params
        if not ap.in_air:
            raise CommandRefused("Orbit refused: vehicle is not flying")
        orbiting = self.active and self.center_m is not None
        here = self.center_m if orbiting and self.center_m is not None else ap.position_m
        center = tuple(here[i] if c is None else c for i, c in enumerate(center_m))
        if not math.isfinite(radius_m):
            radius_m = self.radius_m if orbiting else DEFAULT_RADIUS_M
        r_max = p["MC_ORBIT_RAD_MAX"]
        if not ORBIT_MIN_RADIUS_M <= abs(radius_m) <= r_max:
            raise CommandRefused(f"Orbit: radius {abs(radius_m):.3g} m not in "
                                 f"[{ORBIT_MIN_RADIUS_M:g}, {r_max:g}]")
        if not math.isfinite(speed_m_s) or speed_m_s == 0.0:
            speed_m_s = self.speed_m_s if orbiting else DEFAULT_SPEED_M_S
        if speed_m_s < 0.0:  # PX4: a negative speed reverses the direction
            speed_m_s, radius_m = -speed_m_s, -radius_m
        if math.isfinite(yaw) and int(yaw) in tuple(OrbitYaw):
            behaviour = OrbitYaw(int(yaw))
        elif math.isfinite(yaw):
            raise CommandRefused(f"Orbit: unknown yaw behaviour {yaw:g}")
        else:
            behaviour = self.yaw if orbiting else OrbitYaw(int(p["MC_ORBIT_YAW_MOD"]))
        cx, cy, cz = (float(c) for c in center)
        check_target(p, ap.state.home_m, (cx, cy, cz), "Orbit centre")
        limit = min(p["MPC_XY_VEL_MAX"], math.sqrt(p["MPC_ACC_HOR"] * abs(radius_m)))
        self.center_m = (cx, cy, max(cz, 1.0))
        self.radius_m = radius_m
        self.speed_m_s = min(speed_m_s, limit)
        self.yaw = behaviour
        self._initial_yaw_deg = float(ap.fleet.dyn.yaw_deg[ap.k])
        if not orbiting:
            ap.pause_mission()
            ap.switch_mode(FlightMode.ORBIT)
            ap.event(TruthEventKind.ORBIT, center_m=list(self.center_m), radius_m=radius_m,
                     speed_m_s=self.speed_m_s)
        ap.drop_goal()
        dyn, k = ap.fleet.dyn, ap.k
        dyn.control[k] = dy.CONTROL_VELOCITY
        dyn.tracking[k] = dy.TRACK_NONE
        ap.refresh_busy()
        self.on_step()

    def on_step(self) -> None:
        """The velocity and heading set-points for the next physics step."""
        center = self.center_m
        if center is None:
            return
        ap = self.ap
        dyn, k = ap.fleet.dyn, ap.k
        x, y, z = ap.position_m
        east, north = x - center[0], y - center[1]
        r = math.hypot(east, north)
        ux, uy = (east / r, north / r) if r > 1e-6 else (1.0, 0.0)
        clockwise = 1.0 if self.radius_m > 0.0 else -1.0
        tx, ty = clockwise * uy, -clockwise * ux  # unit tangent in the orbit's direction
        v_max = ap.params["MPC_XY_VEL_MAX"]
        radial = min(max(RADIAL_GAIN_1_S * (abs(self.radius_m) - r), -v_max), v_max)
        vx = self.speed_m_s * tx + radial * ux
        vy = self.speed_m_s * ty + radial * uy
        speed = math.hypot(vx, vy)
        if speed > v_max:
            vx, vy = vx * v_max / speed, vy * v_max / speed
        vz = VERTICAL_GAIN_1_S * (center[2] - z)
        dyn.velocity_sp_m_s[k] = (vx, vy, vz)
        if self.yaw is OrbitYaw.HOLD_FRONT_TO_CIRCLE_CENTER:
            dyn.goal_yaw_deg[k] = _bearing_deg(-east, -north) if r > 1e-6 else math.nan
        elif self.yaw is OrbitYaw.HOLD_FRONT_TANGENT_TO_CIRCLE:
            dyn.goal_yaw_deg[k] = _bearing_deg(tx, ty)
        elif self.yaw is OrbitYaw.UNCONTROLLED:
            dyn.goal_yaw_deg[k] = math.nan
        else:
            dyn.goal_yaw_deg[k] = self._initial_yaw_deg
