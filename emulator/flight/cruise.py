"""Fast-forward through steady flight: how many physics steps provably change nothing but
positions along straight lines at constant velocity, vehicle by vehicle.

A vehicle resting at its goal, or cruising towards it at the speed and heading its commands
ask for, moves at constant velocity until something can happen to it: braking begins, an
acceptance radius or the ground is reached, a battery level or a collision-prevention check
falls due. `cruise_plan` works out that horizon for every vehicle. When every vehicle is steady
the fleet applies the steps in one go (a leap); when only a few are not, those few are stepped
one by one while the steady ones still move in one go (emulator.flight.solo). Either way every
step of the trajectory is recorded, and no step runs past a timer.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np

from emulator.flight.arrays import any_true as _any
from emulator.flight.arrays import count_nonzero as _count
from emulator.flight.arrays import indices as _indices
from emulator.flight.battery import (
    CLIMB_POWER_PER_M_S,
    GROUND_IDLE_POWER,
    SPEED_POWER_PER_M2_S2,
)
from emulator.flight.dynamics import (
    BRAKING_SHARE,
    CONTROL_NONE,
    CONTROL_VELOCITY,
    DEG_PER_RAD,
    TRACK_NONE,
    along_line_limit,
)
from emulator.flight.fleet_view import FleetView

__all__ = ["CruisePlan", "cruise_plan", "steady_steps"]

ACCEL_STEADY_M_S2: Final = 1e-6
YAW_STEADY_DEG: Final = 1e-9
AT_GOAL_M: Final = 1e-6
ALIGNED_COS_TOL: Final = 1e-9  # 1 - cos of the largest angle between velocity and goal direction
MIN_CRUISE_STEPS: Final = 2.0  # a vehicle steady for fewer steps than this is stepped one by one
# Up to this many vehicles the plan is worked out in Python floats, vehicle by vehicle; for
# more, with whole arrays (the same decisions, up to the last bit of a few roundings).
FLOAT_PLAN_MAX_VEHICLES: Final = 32


@dataclass(frozen=True, slots=True)
class CruisePlan:
    """`steps` steps in which every vehicle outside `solo` flies at constant velocity;
    `solo` (ascending indices) are stepped one by one (none: a leap of the whole fleet).
    `states`: each solo vehicle's state as `SoloVehicle` reads it (emulator.flight.solo's
    STATE_FIELDS), read by the plan already; None: read it from the arrays."""

    steps: int
    solo: np.ndarray
    states: list[list[float]] | None = None


def steady_steps(fleet: FleetView, limit: int) -> int:
    """Steps (>= 2) the whole fleet can fast-forward through, or 0 if it must step normally."""
    plan = cruise_plan(fleet, limit, max_solo=0)
    return 0 if plan is None else plan.steps


def cruise_plan(fleet: FleetView, limit: int, *, max_solo: int) -> CruisePlan | None:
    """The next stretch of steady flight, with at most max_solo vehicles stepped one by one;
    None when the fleet must take a plain step (a stretch of a leap is at least 2 steps)."""
    if limit < 1:
        return None
    dyn, dt = fleet.dyn, fleet.dt_s
    if _any(dyn.control == CONTROL_VELOCITY):
        return None  # offboard set-points are checked against the fence every step
    if fleet.fenced:
        return None  # vehicles with a fence plan are checked against it every step
    horizon = float(limit)
    timer = fleet.timer_s.min()
    if math.isfinite(timer):
        horizon = min(horizon, (timer - fleet.now_s) / dt - 1.0)
    if horizon < 1.0 or (max_solo == 0 and horizon < MIN_CRUISE_STEPS):
        return None
    floats: _FleetFloats | None = None
    if dyn.n <= FLOAT_PLAN_MAX_VEHICLES:
        floats = _FleetFloats(fleet)
        steps = _cruise_steps_floats(fleet, max_solo, floats)
    else:
        steps = _cruise_steps_arrays(fleet).tolist()
    if steps is None:
        return None
    solo = [k for k, s in enumerate(steps) if not s >= MIN_CRUISE_STEPS]
    if not solo:
        horizon = min(horizon, min(steps))
        return CruisePlan(int(horizon), _NO_SOLO) if horizon >= MIN_CRUISE_STEPS else None
    if len(solo) > max_solo:
        return None
    if len(solo) < len(steps):
        horizon = min(horizon, min(s for s in steps if s >= MIN_CRUISE_STEPS))
    if horizon < 1.0:
        return None
    states = None if floats is None else [floats.state(k) for k in solo]
    return CruisePlan(int(horizon), np.array(solo, dtype=np.intp), states)


def _cruise_steps_arrays(fleet: FleetView) -> np.ndarray:
    """Per vehicle, the steps it can cruise (-inf: not steady), with whole arrays."""
    dyn, dt, now = fleet.dyn, fleet.dt_s, fleet.now_s
    n = dyn.n
    active = dyn.control != CONTROL_NONE
    # Vehicles that are not in steady flight at all: speeding up, braking or turning.
    unsteady = dyn.yaw_tracking | (np.abs(dyn.accel_m_s2) > ACCEL_STEADY_M_S2).any(axis=1)
    yaw_step = dyn.yaw_step_deg
    if yaw_step is not None:
        unsteady |= np.abs(yaw_step) > YAW_STEADY_DEG
    speed = np.sqrt(np.einsum("ij,ij->i", dyn.velocity_m_s, dyn.velocity_m_s))
    moving = active & (speed > 1e-9)
    err = dyn.goal_m - dyn.position_m
    dist = np.sqrt(np.einsum("ij,ij->i", err, err))
    # At rest off its goal (about to start moving) or on a goal whose arrival the next step
    # reports.
    unsteady |= active & ~moving & ((dist > AT_GOAL_M) | (dyn.tracking != TRACK_NONE))
    steps = np.full(n, math.inf)
    n_moving = _count(moving)
    if n_moving:
        idx = _indices(moving)
        s, d, e = speed[idx], dist[idx], err[idx]
        vel = dyn.velocity_m_s[idx]
        # Steady flight heads straight for the goal. A velocity that does not (a wind the
        # airframe cannot fly against bends or reverses it) is no cruise.
        along = np.einsum("ij,ij->i", vel, e)
        unsteady[idx] |= along < s * d * (1.0 - ALIGNED_COS_TOL)
        d_xy = np.hypot(e[:, 0], e[:, 1])
        h = d_xy / np.maximum(d, 1e-9)
        w = np.abs(e[:, 2]) / np.maximum(d, 1e-9)
        # ... at the speed its commands ask for now (a command since its last step may have
        # changed them), facing where they ask it to face
        vz_lim = np.where(e[:, 2] >= 0.0, dyn.climb_m_s[idx], dyn.descent_m_s[idx])
        s_max = along_line_limit(dyn.speed_xy_m_s[idx], vz_lim, h, w)
        unsteady[idx] |= np.abs(s - s_max) > ACCEL_STEADY_M_S2 * dt
        goal_yaw, yaw = dyn.goal_yaw_deg[idx], dyn.yaw_deg[idx]
        free = np.isnan(goal_yaw)
        bearing = np.degrees(np.arctan2(e[:, 0], e[:, 1]))
        desired = np.where(free, np.where(d_xy > 2.0, bearing, yaw), goal_yaw)
        unsteady[idx] |= np.abs((desired - yaw + 540.0) % 360.0 - 180.0) > YAW_STEADY_DEG
        a_eff = along_line_limit(dyn.accel_xy_m_s2[idx], dyn.accel_z_m_s2[idx], h, w)
        step_m = s * dt
        braking_m = s * s / (2.0 * BRAKING_SHARE * a_eff)
        free_m = d - braking_m
        tracked = dyn.tracking[idx] != TRACK_NONE
        free_m = np.where(tracked, np.minimum(free_m, d - dyn.acceptance_m[idx]), free_m)
        vz = vel[:, 2]
        ground_m = np.where(vz < 0.0, dyn.position_m[idx, 2] / np.maximum(-vz, 1e-9) * s, np.inf)
        free_m = np.minimum(free_m, ground_m)
        cruise = free_m / step_m - 2.0
        if fleet.guard.enabled:
            cruise = np.minimum(cruise, (fleet.guard.check_at_s[idx] - now) / dt - 1.0)
        steps[idx] = cruise
    steps = np.minimum(steps, _battery_horizon_steps(fleet))
    steps[unsteady] = -math.inf
    return steps


class _FleetFloats:
    """The fleet's arrays that the plan and the solo vehicles read, as Python lists (typed:
    the compiled plan works on C doubles, not on Python objects)."""

    def __init__(self, fleet: FleetView) -> None:
        dyn = fleet.dyn
        n = dyn.n
        yaw_step = dyn.yaw_step_deg
        self.yaw_steps: list[float] = [0.0] * n if yaw_step is None else yaw_step.tolist()
        self.check_at: list[float] = (fleet.guard.check_at_s.tolist() if fleet.guard.enabled
                                      else [_INF] * n)
        self.accel_xy: list[float] = dyn.accel_xy_m_s2.tolist()
        self.accel_z: list[float] = dyn.accel_z_m_s2.tolist()
        self.acceptance: list[float] = dyn.acceptance_m.tolist()
        self.speed_xy: list[float] = dyn.speed_xy_m_s.tolist()
        self.climb: list[float] = dyn.climb_m_s.tolist()
        self.descent: list[float] = dyn.descent_m_s.tolist()
        self.goal_yaws: list[float] = dyn.goal_yaw_deg.tolist()
        self.yaws: list[float] = dyn.yaw_deg.tolist()
        self.controls: list[int] = dyn.control.tolist()
        self.trackings: list[int] = dyn.tracking.tolist()
        self.yaw_trackings: list[bool] = dyn.yaw_tracking.tolist()
        self.accels: list[list[float]] = dyn.accel_m_s2.tolist()
        self.velocities: list[list[float]] = dyn.velocity_m_s.tolist()
        self.positions: list[list[float]] = dyn.position_m.tolist()
        self.goals: list[list[float]] = dyn.goal_m.tolist()

    def state(self, k: int) -> list[float]:
        """Vehicle k's state in the order of emulator.flight.solo's STATE_FIELDS."""
        p, v, a, g = self.positions[k], self.velocities[k], self.accels[k], self.goals[k]
        return [p[0], p[1], p[2], v[0], v[1], v[2], a[0], a[1], a[2], self.yaws[k],
                float(self.trackings[k]), 1.0 if self.yaw_trackings[k] else 0.0,
                float(self.controls[k]), g[0], g[1], g[2], self.goal_yaws[k], self.speed_xy[k],
                self.accel_xy[k], self.accel_z[k], self.climb[k], self.descent[k],
                self.acceptance[k]]


def _cruise_steps_floats(fleet: FleetView, max_solo: int | None = None,
                         floats: _FleetFloats | None = None) -> list[float] | None:
    """`_cruise_steps_arrays` vehicle by vehicle in Python floats (cheaper for a few); None
    as soon as more than max_solo vehicles cannot cruise for MIN_CRUISE_STEPS."""
    dyn, dt, now = fleet.dyn, fleet.dt_s, fleet.now_s
    n = dyn.n
    short_left = n if max_solo is None else max_solo
    f = _FleetFloats(fleet) if floats is None else floats
    yaw_steps, check_at, accel_xy, accel_z = f.yaw_steps, f.check_at, f.accel_xy, f.accel_z
    acceptance, speed_xy, climb, descent = f.acceptance, f.speed_xy, f.climb, f.descent
    goal_yaws, yaws, controls, trackings = f.goal_yaws, f.yaws, f.controls, f.trackings
    yaw_trackings, accels, velocities = f.yaw_trackings, f.accels, f.velocities
    positions, goals = f.positions, f.goals
    battery = _BatteryFloats(fleet)
    speed_tol = ACCEL_STEADY_M_S2 * dt
    steps: list[float] = []
    for k in range(n):
        control, tracking, yaw_tracking = controls[k], trackings[k], yaw_trackings[k]
        accel, velocity, p, g = accels[k], velocities[k], positions[k], goals[k]
        ax, ay, az = accel[0], accel[1], accel[2]
        vx, vy, vz = velocity[0], velocity[1], velocity[2]
        if (yaw_tracking or abs(ax) > ACCEL_STEADY_M_S2 or abs(ay) > ACCEL_STEADY_M_S2
                or abs(az) > ACCEL_STEADY_M_S2 or abs(yaw_steps[k]) > YAW_STEADY_DEG):
            value = _NEG_INF  # speeding up, braking or turning
        else:
            value = _vehicle_steps(k, control, tracking, vx, vy, vz, p, g, speed_xy[k],
                                   climb[k], descent[k], accel_xy[k], accel_z[k],
                                   acceptance[k], goal_yaws[k], yaws[k],
                                   (check_at[k] - now) / dt - 1.0, dt, speed_tol,
                                   battery)
        if not value >= MIN_CRUISE_STEPS:
            short_left -= 1
            if short_left < 0:
                return None
        steps.append(value)
    return steps


def _vehicle_steps(k: int, control: int, tracking: int, vx: float, vy: float, vz: float,
                   p: list[float], g: list[float], speed_xy: float, climb: float,
                   descent: float, accel_xy: float, accel_z: float, acceptance: float,
                   goal_yaw: float, yaw: float, guard_steps: float, dt: float,
                   speed_tol: float, battery: _BatteryFloats) -> float:
    """The steps one vehicle with no acceleration and no yaw change can cruise (-inf: none)."""
    pz = p[2]
    ex, ey, ez = g[0] - p[0], g[1] - p[1], g[2] - pz
    s = math.sqrt(vx * vx + vy * vy + vz * vz)
    d = math.sqrt(ex * ex + ey * ey + ez * ez)
    if control == CONTROL_NONE or not s > 1e-9:
        at_rest = control == CONTROL_NONE or (d <= AT_GOAL_M and tracking == TRACK_NONE)
        return battery.steps(k, vx, vy, vz) if at_rest else _NEG_INF
    if vx * ex + vy * ey + vz * ez < s * d * (1.0 - ALIGNED_COS_TOL):
        return _NEG_INF  # not heading straight for the goal
    d_min = d if d > 1e-9 else 1e-9
    d_xy = _hypot(ex, ey)
    h, w = d_xy / d_min, abs(ez) / d_min
    vz_lim = climb if ez >= 0.0 else descent
    # the along-line limits (dynamics.along_line_limit) of the speed and the acceleration
    if h > 0.0:
        speed_h, accel_h = speed_xy / h, accel_xy / h
    else:
        speed_h = accel_h = _INF
    if w > 0.0:
        speed_v, accel_v = vz_lim / w, accel_z / w
    else:
        speed_v = accel_v = _INF
    along = speed_h if speed_h <= speed_v else speed_v
    if along == _INF:
        along = speed_xy if speed_xy <= vz_lim else vz_lim
    if abs(s - along) > speed_tol:
        return _NEG_INF  # not at the speed its commands ask for now
    if goal_yaw != goal_yaw:  # free: facing the goal when more than 2 m away
        desired = _atan2(ex, ey) * DEG_PER_RAD if d_xy > 2.0 else yaw
    else:
        desired = goal_yaw
    if abs((desired - yaw + 540.0) % 360.0 - 180.0) > YAW_STEADY_DEG:
        return _NEG_INF  # about to turn
    a_eff = accel_h if accel_h <= accel_v else accel_v
    if a_eff == _INF:
        a_eff = accel_xy if accel_xy <= accel_z else accel_z
    free_m = d - s * s / (2.0 * BRAKING_SHARE * a_eff)
    if tracking != TRACK_NONE:
        free_m = min(free_m, d - acceptance)
    if vz < 0.0:
        free_m = min(free_m, pz / max(-vz, 1e-9) * s)
    # two-argument min: compiled as a float comparison (the same first-smallest rule)
    return min(min(free_m / (s * dt) - 2.0, guard_steps), battery.steps(k, vx, vy, vz))


class _BatteryFloats:
    """`_battery_horizon_steps` for one vehicle at a time, in Python floats."""

    def __init__(self, fleet: FleetView) -> None:
        bat = fleet.bat
        self._pct: list[float] = bat.pct.tolist()
        self._levels: list[list[float]] = bat.levels_pct.T.tolist()
        self._full_pct_s: list[float] = (100.0 / bat.hover_endurance_s).tolist()
        self._charge: list[float] = bat.charge_rate_pct_s.tolist()
        self._airborne: list[bool] = fleet.airborne.tolist()
        self._armed: list[bool] = fleet.armed.tolist()
        wind: list[float] = fleet.dyn.wind_m_s.tolist()
        self._wind_x: float = wind[0]
        self._wind_y: float = wind[1]
        self._dt: float = fleet.dt_s
        self._slack: float = 2.0 * fleet.battery_every_steps

    def steps(self, k: int, vx: float, vy: float, vz: float) -> float:
        if self._airborne[k]:
            air = _hypot(vx - self._wind_x, vy - self._wind_y)
            power = 1.0 + SPEED_POWER_PER_M2_S2 * (air * air) + CLIMB_POWER_PER_M_S * max(vz, 0.0)
        else:
            power = GROUND_IDLE_POWER if self._armed[k] else 0.0
        rate = self._full_pct_s[k] * power - self._charge[k]
        pct = self._pct[k]
        if rate > 0.0:
            # the nearest level below: pct less the highest one (subtraction keeps the order)
            highest = _NEG_INF
            for level in self._levels[k]:
                if highest < level < pct:
                    highest = level
            if highest == _NEG_INF:
                return _INF
            return (pct - highest) / rate / self._dt - self._slack
        if rate < 0.0:
            return (100.0 - pct) / -rate / self._dt - self._slack
        return _INF


_NO_SOLO = np.empty(0, dtype=np.intp)
_INF: Final = math.inf
_NEG_INF: Final = -math.inf
# Bound once, as in emulator.flight.solo (math.sqrt is compiled to C's sqrt where called as such).
_hypot: Final = math.hypot
_atan2: Final = math.atan2


def _battery_horizon_steps(fleet: FleetView) -> np.ndarray:
    """Per vehicle, the steps before its battery could cross a level (low, critical,
    emergency, empty, full) at its present drain or charge rate."""
    bat, dyn, dt = fleet.bat, fleet.dyn, fleet.dt_s
    rate = bat.drain_pct_s(fleet.airborne, fleet.armed, dyn.airspeed_m_s(),
                           dyn.velocity_m_s[:, 2]) - bat.charge_rate_pct_s
    pct = bat.pct
    steps = np.full(pct.size, math.inf)
    draining = rate > 0.0
    if _any(draining):
        levels = bat.levels_pct
        gaps = np.where(levels < pct, pct - levels, np.inf).min(axis=0)
        steps[draining] = gaps[draining] / rate[draining] / dt
    charging = rate < 0.0
    if _any(charging):
        steps[charging] = (100.0 - pct[charging]) / -rate[charging] / dt
    return steps - 2.0 * fleet.battery_every_steps
