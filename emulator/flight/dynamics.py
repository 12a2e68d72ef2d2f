"""Vectorised point-mass kinematics for the whole fleet, stepped at a fixed dt.

Every vehicle is a point mass whose velocity follows a commanded set-point under
acceleration limits: horizontal speed, climb and descent rates, horizontal and vertical
acceleration, a yaw-rate limit and a maximum airspeed against the session's wind. A position
goal is flown along the straight 3D line to it with a braking profile, so arrival is smooth
and never overshoots; nothing ever jumps. State is stored as ``(n, 3)`` arrays in ENU metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final, Protocol

import numpy as np

from emulator.flight.arrays import count_nonzero as _count
from emulator.flight.arrays import indices as _indices
from emulator.networks import MAX_FLEET_VEHICLES

__all__ = [
    "CONTROL_NONE",
    "CONTROL_POSITION",
    "CONTROL_VELOCITY",
    "TRACK_NONE",
    "TRACK_PASS",
    "TRACK_SETTLE",
    "FleetDynamics",
    "StepEvents",
    "StepGuard",
    "along_line_limit",
]

CONTROL_NONE: Final = 0  # resting on the ground: no motion
CONTROL_POSITION: Final = 1  # fly to `goal_m`
CONTROL_VELOCITY: Final = 2  # follow `velocity_sp_m_s`

TRACK_NONE: Final = 0  # no arrival report wanted
TRACK_PASS: Final = 1  # report once inside the acceptance radius
TRACK_SETTLE: Final = 2  # report once inside the acceptance radius and settled

SETTLED_SPEED_M_S: Final = 0.3
# A settled arrival is also this close to the goal. Flown in, the braking profile is well
# inside it by the time the speed drops below SETTLED_SPEED_M_S; the bound matters for a
# vehicle at rest when a goal is set within the acceptance radius (a 1 m take-off, a 1.5 m
# move), which would otherwise count as arrived before it moved.
SETTLED_GOAL_M: Final = 0.1
BRAKING_SHARE: Final = 0.8
# 180 / pi as a double: x * DEG_PER_RAD is math.degrees(x) to the last bit (CPython multiplies
# by the same constant; tests/test_native.py checks it), without a call into the math module.
DEG_PER_RAD: Final = 57.29577951308232
YAW_REACHED_DEG: Final = 1.0
_EMPTY = np.empty(0, dtype=np.intp)


class StepGuard(Protocol):
    """Collision prevention as the step sees it (emulator.flight.collision)."""

    def due(self, active: np.ndarray) -> np.ndarray | None:
        """Mask of the active vehicles whose clearance must be measured this step (None:
        none)."""

    def __call__(self, candidates: np.ndarray, new_pos: np.ndarray) -> np.ndarray:
        """Indices among candidates whose new position lies inside an obstacle."""


@dataclass(frozen=True, slots=True)
class StepEvents:
    """Indices of vehicles for which something happened during one step."""

    arrived: np.ndarray
    yaw_reached: np.ndarray
    touched_down: np.ndarray
    obstacle_stop: np.ndarray

    @property
    def empty(self) -> bool:
        return not (
            self.arrived.size or self.yaw_reached.size or self.touched_down.size
            or self.obstacle_stop.size
        )


_NO_EVENTS = StepEvents(_EMPTY, _EMPTY, _EMPTY, _EMPTY)


def along_line_limit(limit_h: np.ndarray, limit_v: np.ndarray, h: np.ndarray,
                     w: np.ndarray) -> np.ndarray:
    """The largest magnitude along a line whose horizontal share is h and vertical share w
    (direction cosines) that keeps its horizontal part within limit_h and its vertical part
    within limit_v. A limit whose share is zero does not apply: a vertical climb is bounded
    by the climb rate alone, however low the horizontal speed. A zero-length line gets the
    smaller limit."""
    along_h = np.divide(limit_h, h, out=np.full(h.shape, np.inf), where=h > 0.0)
    along_v = np.divide(limit_v, w, out=np.full(w.shape, np.inf), where=w > 0.0)
    along = np.minimum(along_h, along_v)
    return np.where(np.isfinite(along), along, np.minimum(limit_h, limit_v))


def _along_line_limits(limit_h: np.ndarray, limit_v: np.ndarray, h: np.ndarray,
                       w: np.ndarray, along_h: np.ndarray, along_v: np.ndarray) -> np.ndarray:
    """`along_line_limit` for (n, 2) columns of limits at once, in the scratch arrays
    along_h and along_v; element for element the same numbers."""
    along_h.fill(np.inf)
    np.divide(limit_h, h[:, None], out=along_h, where=(h > 0.0)[:, None])
    along_v.fill(np.inf)
    np.divide(limit_v, w[:, None], out=along_v, where=(w > 0.0)[:, None])
    along = np.minimum(along_h, along_v)
    finite = np.isfinite(along)
    if _count(finite) == finite.size:
        return along
    return np.where(finite, along, np.minimum(limit_h, limit_v))


class FleetDynamics:
    """State and limits of n vehicles; `step(dt_s)` advances all of them at once."""

    def __init__(self, n: int) -> None:
        if not 1 <= n <= MAX_FLEET_VEHICLES:
            raise ValueError(f"a fleet holds 1 to {MAX_FLEET_VEHICLES} vehicles, got {n}")
        self.n = n
        self.position_m = np.zeros((n, 3))
        self.velocity_m_s = np.zeros((n, 3))
        self.accel_m_s2 = np.zeros((n, 3))
        self.yaw_deg = np.zeros(n)
        # commands
        self.control = np.zeros(n, dtype=np.int8)
        self.goal_m = np.zeros((n, 3))
        self.goal_yaw_deg = np.full(n, np.nan)
        self.velocity_sp_m_s = np.zeros((n, 3))
        self.tracking = np.zeros(n, dtype=np.int8)
        self.yaw_tracking = np.zeros(n, dtype=bool)
        # limits; the horizontal speed and acceleration limits are the columns of one array
        # (and the vertical acceleration limit a column of another) so that both limits
        # along the line to a goal are worked out together
        self._lim_h = np.empty((n, 2))
        self._lim_v = np.zeros((n, 2))
        self._along_h = np.empty((n, 2))
        self._along_v = np.empty((n, 2))
        self.speed_xy_m_s = self._lim_h[:, 0]
        self.speed_xy_m_s[:] = 8.0
        self.accel_xy_m_s2 = self._lim_h[:, 1]
        self.accel_xy_m_s2[:] = 3.0
        self.accel_z_m_s2 = self._lim_v[:, 1]
        self.accel_z_m_s2[:] = 4.0
        self.airspeed_max_m_s = np.full(n, 12.0)
        self.climb_m_s = np.full(n, 3.0)
        self.descent_m_s = np.full(n, 1.5)
        self.yaw_rate_deg_s = np.full(n, 45.0)
        self.acceptance_m = np.full(n, 2.0)
        self.wind_m_s = np.zeros(2)
        # the yaw change of every vehicle in the last step (None: no vehicle turned)
        self.yaw_step_deg: np.ndarray | None = None

    # ------------------------------------------------------------------ step
    def step(self, dt_s: float, guard: StepGuard | None = None) -> StepEvents:
        """Advance every vehicle by dt_s.

        `guard(due, new_position) -> indices` is collision prevention's safety net: a vehicle
        whose next position it rejects stops where it is. `guard.due(active)` first narrows
        the active vehicles to those whose clearance must be measured this step.
        """
        control = self.control
        active = control != CONTROL_NONE
        n_active = _count(active)
        if not n_active:
            return _NO_EVENTS
        every = n_active == self.n
        pos = self.position_m
        err = self.goal_m - pos
        d_xy = np.hypot(err[:, 0], err[:, 1])
        v_des = self._desired_velocity(err, d_xy, dt_s)
        v_new = self._accel_limited(v_des, dt_s)
        if not every:
            v_new[~active] = 0.0
        new_pos = pos + v_new * dt_s
        below = new_pos[:, 2] < 0.0
        any_below = _count(below)
        if any_below:
            new_pos[below, 2] = 0.0
            v_new[below, 2] = np.maximum(v_new[below, 2], 0.0)
        stopped = _EMPTY
        if guard is not None:
            due = guard.due(active)
            if due is not None:
                moving = _indices(due & (np.abs(v_new).sum(axis=1) > 0.0))
                stopped = guard(moving, new_pos)
                if stopped.size:
                    new_pos[stopped] = pos[stopped]
                    v_new[stopped] = 0.0
        self.accel_m_s2 = (v_new - self.velocity_m_s) * (1.0 / dt_s)
        self.velocity_m_s = v_new
        self.position_m = new_pos
        yaw_reached = self._step_yaw(dt_s, active, every, err, d_xy)
        arrived = self._arrivals()
        touched = self._touchdowns(below) if any_below else _EMPTY
        if arrived.size or yaw_reached.size or touched.size or stopped.size:
            return StepEvents(arrived, yaw_reached, touched, stopped)
        return _NO_EVENTS

    def _desired_velocity(self, err: np.ndarray, d_xy: np.ndarray, dt_s: float) -> np.ndarray:
        d_z = err[:, 2]
        dist = np.sqrt(d_xy * d_xy + d_z * d_z)
        inv = 1.0 / np.maximum(dist, 1e-9)
        h = d_xy * inv
        w = np.abs(d_z) * inv
        # Both limits along the line at once: column 0 speed (horizontal speed against the
        # climb or descent rate), column 1 acceleration.
        lim_v = self._lim_v
        vz_lim = lim_v[:, 0]
        np.copyto(vz_lim, self.descent_m_s)
        np.copyto(vz_lim, self.climb_m_s, where=d_z >= 0.0)
        limits = _along_line_limits(self._lim_h, lim_v, h, w, self._along_h, self._along_v)
        s_max = limits[:, 0]
        a_eff = limits[:, 1]
        # Braking follows v = sqrt(2 a' d) with a' a little below the limit, so the discrete
        # accel-limited velocity can track it and the vehicle stops on the goal, no overshoot.
        braking = np.sqrt(2.0 * BRAKING_SHARE * a_eff * dist)
        speed = np.minimum(np.minimum(s_max, braking), dist * (1.0 / dt_s))
        v_des = err * (speed * inv)[:, None]
        is_vel = self.control == CONTROL_VELOCITY
        if _count(is_vel):
            sp = self.velocity_sp_m_s[is_vel].copy()
            sp[:, 2] = np.clip(sp[:, 2], -self.descent_m_s[is_vel], self.climb_m_s[is_vel])
            v_des[is_vel] = sp
        return v_des

    def _accel_limited(self, v_des: np.ndarray, dt_s: float) -> np.ndarray:
        vel = self.velocity_m_s
        dv = v_des - vel
        dv_xy = np.hypot(dv[:, 0], dv[:, 1])
        scale = np.minimum(1.0, self.accel_xy_m_s2 * dt_s / np.maximum(dv_xy, 1e-12))
        dv[:, :2] *= scale[:, None]
        lim_z = self.accel_z_m_s2 * dt_s
        dv[:, 2] = np.minimum(np.maximum(dv[:, 2], -lim_z), lim_z)
        v_new = vel + dv
        # The airframe cannot exceed its airspeed limit: in strong wind it drifts.
        if self._windy:
            air = v_new[:, :2] - self.wind_m_s
            air_speed = np.hypot(air[:, 0], air[:, 1])
        elif _count(dv_xy > 0):  # calm: the airspeed is the ground speed (v - 0 is v)
            air_speed = np.hypot(v_new[:, 0], v_new[:, 1])
        else:
            return v_new
        over = air_speed > self.airspeed_max_m_s
        if _count(over):
            air = v_new[:, :2] - self.wind_m_s
            air[over] *= (self.airspeed_max_m_s[over] / air_speed[over])[:, None]
            v_new[:, :2] = air + self.wind_m_s
        return v_new

    @property
    def wind_m_s(self) -> np.ndarray:
        """The wind (east, north) in m/s; assign a new array to change it (the step keeps
        whether there is any)."""
        return self._wind_m_s

    @wind_m_s.setter
    def wind_m_s(self, value: np.ndarray) -> None:
        self._wind_m_s = value
        self._windy = bool(_count(value))
        self._wind_speed_m_s = float(np.hypot(value[0], value[1]))

    @property
    def wind_speed_m_s(self) -> float:
        """The wind's speed in m/s (numpy's hypot of the wind)."""
        return self._wind_speed_m_s

    @property
    def windy(self) -> bool:
        """Whether there is any wind."""
        return self._windy

    def _step_yaw(self, dt_s: float, active: np.ndarray, every: bool, err: np.ndarray,
                  d_xy: np.ndarray) -> np.ndarray:
        goal = self.goal_yaw_deg
        yaw = self.yaw_deg
        free = np.isnan(goal)
        far = free & (self.control == CONTROL_POSITION) & (d_xy > 2.0)
        n_far = _count(far)
        if n_far:
            bearing = np.degrees(np.arctan2(err[:, 0], err[:, 1]))
            desired = bearing if n_far == self.n else np.where(
                far, bearing, np.where(free, yaw, goal))
        elif _count(free) == self.n:
            self.yaw_step_deg = None
            return _EMPTY
        else:
            desired = np.where(free, yaw, goal)
        diff = (desired - yaw + 540.0) % 360.0 - 180.0
        limit = self.yaw_rate_deg_s * dt_s
        step = np.minimum(np.maximum(diff, -limit), limit)
        if not every:
            step[~active] = 0.0
        self.yaw_step_deg = step
        self.yaw_deg = (yaw + step) % 360.0
        if not _count(self.yaw_tracking):
            return _EMPTY
        done = self.yaw_tracking & (np.abs(diff - step) < YAW_REACHED_DEG)
        idx = _indices(done)
        if idx.size:
            self.yaw_tracking[idx] = False
        return idx

    def _arrivals(self) -> np.ndarray:
        tracking = self.tracking
        if not _count(tracking):
            return _EMPTY
        err = self.goal_m - self.position_m
        dist2 = np.einsum("ij,ij->i", err, err)
        inside = dist2 <= self.acceptance_m**2
        if not _count(inside):
            return _EMPTY
        settled = (np.einsum("ij,ij->i", self.velocity_m_s, self.velocity_m_s)
                   <= SETTLED_SPEED_M_S**2) & (dist2 <= SETTLED_GOAL_M**2)
        done = inside & ((tracking == TRACK_PASS) | ((tracking == TRACK_SETTLE) & settled))
        idx = _indices(done)
        if idx.size:
            tracking[idx] = TRACK_NONE
        return idx

    def _touchdowns(self, below: np.ndarray) -> np.ndarray:
        descending = np.where(self.control == CONTROL_VELOCITY, self.velocity_sp_m_s[:, 2],
                              self.goal_m[:, 2]) < 0.0
        landing = below & descending & (self.control != CONTROL_NONE)
        return _indices(landing)

    # ----------------------------------------------------------------- helpers
    def speed_m_s(self, k: int) -> float:
        v = self.velocity_m_s[k]
        return math.sqrt(float(v @ v))

    def airspeed_m_s(self) -> np.ndarray:
        air = self.velocity_m_s[:, :2] - self.wind_m_s
        return np.hypot(air[:, 0], air[:, 1])
