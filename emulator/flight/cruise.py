"""Fast-forward through steady flight: how many physics steps provably change nothing but
positions along straight lines at constant velocity.

When every vehicle is either resting at its goal or cruising at its speed limit towards it,
the next steps are pure constant-velocity motion until something can happen: braking
begins, an acceptance radius or the ground is reached, a timer fires, a battery level or a
collision-prevention check falls due. `steady_steps` computes that horizon; the fleet then
applies those steps in one go, still recording every step of the trajectory.
"""

from __future__ import annotations

import math

import numpy as np

from emulator.flight.arrays import any_true as _any
from emulator.flight.arrays import count_nonzero as _count
from emulator.flight.arrays import indices as _indices
from emulator.flight.dynamics import (
    BRAKING_SHARE,
    CONTROL_NONE,
    CONTROL_POSITION,
    TRACK_NONE,
    along_line_limit,
)
from emulator.flight.fleet_view import FleetView

__all__ = ["steady_steps"]

ACCEL_STEADY_M_S2 = 1e-6
AT_GOAL_M = 1e-6
ALIGNED_COS_TOL = 1e-9  # 1 - cos of the largest angle between velocity and goal direction


def steady_steps(fleet: FleetView, limit: int) -> int:
    """Steps (>= 2) the fleet can fast-forward through, or 0 if it must step normally."""
    if limit < 2:
        return 0
    dyn, dt = fleet.dyn, fleet.dt_s
    if _any(np.abs(dyn.accel_m_s2) > ACCEL_STEADY_M_S2) or _any(dyn.yaw_tracking):
        return 0
    if dyn.yaw_stepped_over(1e-9):
        return 0
    active = dyn.control != CONTROL_NONE
    if _any(active & (dyn.control != CONTROL_POSITION)):
        return 0
    horizon = float(limit)
    speed = np.sqrt(np.einsum("ij,ij->i", dyn.velocity_m_s, dyn.velocity_m_s))
    moving = active & (speed > 1e-9)
    err = dyn.goal_m - dyn.position_m
    dist = np.sqrt(np.einsum("ij,ij->i", err, err))
    if _any(active & ~moving & (dist > AT_GOAL_M)):
        return 0  # about to start moving
    if _any(active & ~moving & (dyn.tracking != TRACK_NONE)):
        return 0  # at rest on a goal whose arrival the next step reports
    n_moving = _count(moving)
    if n_moving:
        # Every vehicle moving (the common case): whole arrays, not copies of their rows.
        idx: slice | np.ndarray = slice(None) if n_moving == moving.size else _indices(moving)
        s, d, e = speed[idx], dist[idx], err[idx]
        vel = dyn.velocity_m_s[idx]
        # Steady flight heads straight for the goal. A velocity that does not (a wind the
        # airframe cannot fly against bends or reverses it) is no cruise: step normally.
        along = np.einsum("ij,ij->i", vel, e)
        if _any(along < s * d * (1.0 - ALIGNED_COS_TOL)):
            return 0
        h = np.hypot(e[:, 0], e[:, 1]) / np.maximum(d, 1e-9)
        w = np.abs(e[:, 2]) / np.maximum(d, 1e-9)
        a_eff = along_line_limit(dyn.accel_xy_m_s2[idx], dyn.accel_z_m_s2[idx], h, w)
        step_m = s * dt
        braking_m = s * s / (2.0 * BRAKING_SHARE * a_eff)
        free_m = d - braking_m
        tracked = dyn.tracking[idx] != TRACK_NONE
        free_m = np.where(tracked, np.minimum(free_m, d - dyn.acceptance_m[idx]), free_m)
        vz = vel[:, 2]
        ground_m = np.where(vz < 0.0, dyn.position_m[idx, 2] / np.maximum(-vz, 1e-9) * s, np.inf)
        free_m = np.minimum(free_m, ground_m)
        horizon = min(horizon, float((free_m / step_m).min()) - 2.0)
        if fleet.guard.enabled:
            due = fleet.guard.check_at_s[idx].min()
            horizon = min(horizon, (due - fleet.now_s) / dt - 1.0)
    timer = fleet.timer_s.min()
    if math.isfinite(timer):
        horizon = min(horizon, (timer - fleet.now_s) / dt - 1.0)
    horizon = min(horizon, _battery_horizon_steps(fleet, moving))
    return int(horizon) if horizon >= 2.0 else 0


def _battery_horizon_steps(fleet: FleetView, moving: np.ndarray) -> float:
    """Steps before any battery could cross a level (low, critical, emergency, empty, full)."""
    bat, dyn, dt = fleet.bat, fleet.dyn, fleet.dt_s
    rate = bat.drain_pct_s(fleet.airborne, fleet.armed, dyn.airspeed_m_s(),
                           dyn.velocity_m_s[:, 2]) - bat.charge_rate_pct_s
    pct = bat.pct
    horizon = math.inf
    draining = rate > 0.0
    if _any(draining):
        levels = bat.levels_pct
        gaps = np.where(levels < pct, pct - levels, np.inf).min(axis=0)
        horizon = float((gaps[draining] / rate[draining]).min()) / dt
    charging = rate < 0.0
    if _any(charging):
        horizon = min(horizon, float(((100.0 - pct[charging]) / -rate[charging]).min()) / dt)
    return horizon - 2.0 * fleet.battery_every_steps
