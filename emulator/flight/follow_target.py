"""Follow-target mode (PX4's AUTO_FOLLOW_TARGET): follow a target a ground station reports.

The target's fixes arrive as FOLLOW_TARGET messages (MAVSDK's follow_me plugin, a phone's
position in QGroundControl). Between fixes the target is extrapolated with the velocity it
reported, in simulated time; where a new fix jumps from the extrapolation, the estimate
moves over with a first-order lag of FLW_TGT_RS seconds (PX4's responsiveness: 0 takes every
fix at once), so a steadily moving target is estimated without lag. The vehicle flies by velocity
to its follow point: FLW_TGT_DST from the target at the follow angle FLW_TGT_FA measured from
the target's course (0 in front, 90 right, 180 behind, -90 left), at FLW_TGT_HT above home
(FLW_TGT_ALT_M 0, and 1 on this flat ground) or above the target (2), its front towards the
target. The target's velocity is fed forward, so a steadily moving target is followed at the
distance without lag. While the follow angle changes (on entry, or as the target turns) the
vehicle circles the target at up to FLW_TGT_MAX_VEL. A target that stops sending for
TARGET_TIMEOUT_S (wall seconds: a link rule) is taken as standing still where it was last
estimated: the vehicle holds its follow point there until fixes come again.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from emulator.flight import dynamics as dy
from emulator.flight.modes import FlightMode
from emulator.flight.refusal import CommandRefused, Severity
from emulator.flight.vehicle_control import VehicleControl
from emulator.truth_events import TruthEventKind

__all__ = ["TARGET_TIMEOUT_S", "FollowTarget", "TargetFix"]

Vec3 = tuple[float, float, float]
TARGET_TIMEOUT_S = 2.5  # wall seconds without a fix: the target is lost
COURSE_MIN_SPEED_M_S = 0.3  # slower than this the target's course is kept, not followed
POSITION_GAIN_1_S = 1.0  # velocity per metre off the follow point
ALTITUDE_MODE_TARGET = 2  # FLW_TGT_ALT_M: follow the target's altitude


class TargetFix(NamedTuple):
    position_m: Vec3  # ENU about the session origin
    velocity_m_s: Vec3  # ENU; zero when not reported
    t_s: float  # simulated time of arrival


def _bearing_deg(east: float, north: float) -> float:
    return math.degrees(math.atan2(east, north)) % 360.0


def _turn_deg(from_deg: float, to_deg: float) -> float:
    """The signed shortest turn (deg) from one bearing to another."""
    return (to_deg - from_deg + 180.0) % 360.0 - 180.0


class FollowTarget:
    """The target one vehicle knows of and how it follows it."""

    def __init__(self, autopilot: VehicleControl) -> None:
        self.ap = autopilot
        self.fix: TargetFix | None = None
        self.estimate_m: Vec3 | None = None
        self.angle_deg = 0.0  # bearing from the target to the follow point
        self._course_deg: float | None = None
        self._jump_m: tuple[float, ...] = (0.0, 0.0, 0.0)  # estimate - extrapolation, decaying
        self._received_wall_s = -math.inf
        self._lost = False

    @property
    def active(self) -> bool:
        return self.ap.state.mode is FlightMode.FOLLOW_TARGET

    def update(self, position_m: Vec3, velocity_m_s: Vec3, wall_now_s: float) -> None:
        """A FOLLOW_TARGET fix (ENU m, ENU m/s)."""
        self.fix = TargetFix(position_m, velocity_m_s, self.ap.now_s)
        self._received_wall_s = wall_now_s
        if self.estimate_m is None:  # the first fix: the follow point starts on this side
            self.estimate_m = position_m
            x, y, _ = self.ap.position_m
            self.angle_deg = _bearing_deg(x - position_m[0], y - position_m[1])
        self._jump_m = tuple(e - p for e, p in zip(self.estimate_m, position_m, strict=True))
        if self._lost:
            self._lost = False
            if self.active:
                self.ap.say(Severity.INFO, "Follow target regained")

    def enter(self) -> None:
        ap = self.ap
        if not ap.in_air:
            raise CommandRefused("Follow target refused: vehicle is not flying")
        ap.pause_mission()
        ap.switch_mode(FlightMode.FOLLOW_TARGET)
        self._course_deg = None
        if self.estimate_m is not None:
            x, y, _ = ap.position_m
            self.angle_deg = _bearing_deg(x - self.estimate_m[0], y - self.estimate_m[1])
        ap.drop_goal()
        dyn, k = ap.fleet.dyn, ap.k
        dyn.control[k] = dy.CONTROL_VELOCITY
        dyn.tracking[k] = dy.TRACK_NONE
        ap.event(TruthEventKind.FOLLOW_TARGET,
                 target_m=list(self.estimate_m) if self.estimate_m else None)
        ap.refresh_busy()
        self.on_step(0.0)

    def _raw_target(self) -> tuple[Vec3, Vec3]:
        fix = self.fix
        assert fix is not None
        age_s = self.ap.now_s - fix.t_s
        vel = fix.velocity_m_s
        pos = tuple(p + v * age_s for p, v in zip(fix.position_m, vel, strict=True))
        return (pos[0], pos[1], pos[2]), vel

    def on_step(self, dt_s: float) -> None:
        """The velocity and heading set-points for the next physics step."""
        ap = self.ap
        dyn, k, p = ap.fleet.dyn, ap.k, ap.params
        x, y, z = ap.position_m
        if self.fix is None or self.estimate_m is None:  # no target yet: hold here
            dyn.velocity_sp_m_s[k] = (0.0, 0.0, 0.0)
            dyn.goal_yaw_deg[k] = math.nan
            return
        raw, vel = self._raw_target()
        tau = p["FLW_TGT_RS"]
        keep = 0.0 if tau <= 0.0 else math.exp(-dt_s / tau)
        self._jump_m = tuple(j * keep for j in self._jump_m)
        est = tuple(r + j for r, j in zip(raw, self._jump_m, strict=True))
        self.estimate_m = (est[0], est[1], est[2])
        distance = p["FLW_TGT_DST"]
        if math.hypot(vel[0], vel[1]) >= COURSE_MIN_SPEED_M_S:
            self._course_deg = _bearing_deg(vel[0], vel[1])
        swing_rad_s = 0.0  # how fast the follow point circles the target
        if self._course_deg is not None and dt_s > 0.0:  # circle towards the follow angle
            wanted = (self._course_deg + p["FLW_TGT_FA"]) % 360.0
            step = math.degrees(p["FLW_TGT_MAX_VEL"] / distance) * dt_s
            turn = max(-step, min(step, _turn_deg(self.angle_deg, wanted)))
            self.angle_deg = (self.angle_deg + turn) % 360.0
            swing_rad_s = math.radians(turn) / dt_s
        a = math.radians(self.angle_deg)
        goal_x = est[0] + distance * math.sin(a)
        goal_y = est[1] + distance * math.cos(a)
        base_z = est[2] if int(p["FLW_TGT_ALT_M"]) == ALTITUDE_MODE_TARGET else ap.state.home_m[2]
        goal_z = max(base_z + p["FLW_TGT_HT"], 1.0)
        # fed forward: the target's velocity and the follow point's own swing around it
        vx = vel[0] + swing_rad_s * distance * math.cos(a) + POSITION_GAIN_1_S * (goal_x - x)
        vy = vel[1] - swing_rad_s * distance * math.sin(a) + POSITION_GAIN_1_S * (goal_y - y)
        limit = p["MPC_XY_VEL_MAX"]
        speed = math.hypot(vx, vy)
        if speed > limit:
            vx, vy = vx * limit / speed, vy * limit / speed
        dyn.velocity_sp_m_s[k] = (vx, vy, POSITION_GAIN_1_S * (goal_z - z))
        east, north = est[0] - x, est[1] - y
        dyn.goal_yaw_deg[k] = _bearing_deg(east, north) if math.hypot(east, north) > 1.0 \
            else math.nan

    def check_link(self, wall_now_s: float) -> None:
        """No fix for TARGET_TIMEOUT_S: the target stands where it was last estimated."""
        if self._lost or self.fix is None or not self.active:
            return
        if wall_now_s - self._received_wall_s <= TARGET_TIMEOUT_S:
            return
        self._lost = True
        raw, _ = self._raw_target()
        self.fix = TargetFix(raw, (0.0, 0.0, 0.0), self.ap.now_s)
        self.ap.event(TruthEventKind.FOLLOW_TARGET_LOST, target_m=list(raw))
        self.ap.say(Severity.WARNING, "Follow target lost: holding")
