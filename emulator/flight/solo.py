"""One vehicle stepped on its own, in Python floats.

While most of the fleet cruises (emulator.flight.cruise), the few vehicles that speed up,
brake or turn are stepped one by one: for a handful of vehicles, float arithmetic costs far
less than numpy's calls on whole arrays. `SoloVehicle.step` applies to one vehicle the rules
`FleetDynamics.step` applies to every row, in the same order and with the same operations
(only `math.hypot` and `math.atan2` may round their last bit differently from numpy's).
Vehicles under velocity control are never stepped here.

The module is plain, typed Python that mypyc compiles as well (build_native.py,
emulator.flight.native): the attributes' declared types and the `Final` constants let the
compiled step run on C doubles, with the same operations and so the same results.
"""

from __future__ import annotations

import math
from typing import Final, Protocol

from emulator.flight.dynamics import (
    BRAKING_SHARE,
    CONTROL_NONE,
    CONTROL_POSITION,
    DEG_PER_RAD,
    SETTLED_GOAL_M,
    SETTLED_SPEED_M_S,
    TRACK_NONE,
    TRACK_PASS,
    TRACK_SETTLE,
    YAW_REACHED_DEG,
    FleetDynamics,
)

__all__ = [
    "ARRIVED",
    "OBSTACLE_STOP",
    "STATE_FIELDS",
    "STEADY",
    "TOUCHED_DOWN",
    "YAW_REACHED",
    "SoloBattery",
    "SoloVehicle",
    "run_solo_steps",
    "step_all",
]

# What happened to a solo vehicle in its step (bits of `SoloVehicle.step`'s result).
ARRIVED: Final = 1
YAW_REACHED: Final = 2
TOUCHED_DOWN: Final = 4
OBSTACLE_STOP: Final = 8
STEADY: Final = 16  # no acceleration and no yaw change: it may cruise from here

ACCEL_STEADY_M_S2: Final = 1e-6  # emulator.flight.cruise's bounds
YAW_STEADY_DEG: Final = 1e-9
_SETTLED_SPEED2: Final = SETTLED_SPEED_M_S**2
_SETTLED_GOAL2: Final = SETTLED_GOAL_M**2
_INF: Final = math.inf
# Bound once: the compiled step calls them without looking them up in the math module.
_hypot: Final = math.hypot
_atan2: Final = math.atan2


SOLO_EVENTS: Final = ARRIVED | YAW_REACHED | TOUCHED_DOWN | OBSTACLE_STOP
# A vehicle's state as one list of floats (`SoloVehicle`'s `state`; emulator.flight.cruise's
# plan reads it from the arrays already): the FleetDynamics row of each, in this order.
STATE_FIELDS: Final = ("px", "py", "pz", "vx", "vy", "vz", "ax", "ay", "az", "yaw", "tracking",
                       "yaw_tracking", "control", "gx", "gy", "gz", "goal_yaw", "speed_xy",
                       "accel_xy", "accel_z", "climb", "descent", "acceptance")


class Guard(Protocol):
    """Collision prevention for one vehicle at a time (emulator.flight.collision)."""

    def __call__(self, k: int, t_s: float, x_m: float, y_m: float, z_m: float) -> bool:
        """Whether vehicle k's position at t_s lies inside an obstacle (measured only once
        its clearance deadline has passed)."""

    def check_at_s(self, k: int) -> float:
        """When vehicle k's clearance is next measured."""


class SoloVehicle:
    """Row k of a FleetDynamics as floats: read by the constructor, stepped by `step`,
    written back by `store`. The commands and limits must not change in between."""

    __slots__ = (
        "_accel_xy", "_accel_z", "_acceptance2", "_active", "_airspeed", "_airspeed2_below",
        "_check_at", "_climb", "_descent", "_dt", "_dv_xy_max", "_dv_xy_max2_below", "_dv_z_max",
        "_goal_yaw", "_guard", "_gx", "_gy", "_gz",
        "_inv_dt", "_landing", "_position", "_rows", "_speed_xy", "_wind", "_yaw_step_max", "ax",
        "ay", "az", "k", "moving", "px", "py", "pz", "tracking", "vx", "vy", "vz", "yaw",
        "yaw_step", "yaw_tracking",
    )

    k: int
    px: float
    py: float
    pz: float
    vx: float
    vy: float
    vz: float
    ax: float
    ay: float
    az: float
    yaw: float
    yaw_step: float
    tracking: int
    yaw_tracking: bool
    moving: bool
    _active: bool
    _position: bool
    _landing: bool
    _gx: float
    _gy: float
    _gz: float
    _goal_yaw: float
    _speed_xy: float
    _accel_xy: float
    _accel_z: float
    _airspeed: float
    _airspeed2_below: float
    _climb: float
    _descent: float
    _dv_xy_max: float
    _dv_xy_max2_below: float
    _dv_z_max: float
    _yaw_step_max: float
    _acceptance2: float
    _dt: float
    _inv_dt: float
    _check_at: float
    _rows: list[float]
    _wind: list[float] | None
    _guard: Guard | None

    def __init__(self, dyn: FleetDynamics, k: int, dt_s: float, guard: Guard | None,
                 rows: list[float] | None = None, state: list[float] | None = None) -> None:
        """rows: where each step appends the vehicle's x, y, z, yaw and moving (1.0 or 0.0);
        state: row k of dyn's arrays in the order of STATE_FIELDS (None: read here)."""
        self.k = k
        self._rows = [] if rows is None else rows
        s = _state(dyn, k) if state is None else state
        self.px, self.py, self.pz = s[0], s[1], s[2]
        self.vx, self.vy, self.vz = s[3], s[4], s[5]
        self.ax, self.ay, self.az = s[6], s[7], s[8]
        self.yaw = s[9]
        self.yaw_step = 0.0
        self.tracking = int(s[10])
        self.yaw_tracking = s[11] != 0.0
        self.moving = False
        control = int(s[12])
        self._active = control != CONTROL_NONE
        self._position = control == CONTROL_POSITION
        self._gx, self._gy, self._gz = s[13], s[14], s[15]
        self._landing = self._active and self._gz < 0.0
        self._goal_yaw = s[16]
        self._speed_xy = s[17]
        self._accel_xy = s[18]
        self._accel_z = s[19]
        self._climb = s[20]
        self._descent = s[21]
        self._airspeed = float(dyn.airspeed_max_m_s[k])
        self._dv_xy_max = self._accel_xy * dt_s
        self._airspeed2_below = _surely_below(self._airspeed)
        self._dv_xy_max2_below = _surely_below(self._dv_xy_max)
        self._dv_z_max = self._accel_z * dt_s
        self._yaw_step_max = float(dyn.yaw_rate_deg_s[k]) * dt_s
        acceptance = s[22]
        self._acceptance2 = acceptance * acceptance
        self._wind = dyn.wind_m_s.tolist() if dyn.windy else None
        self._dt = dt_s
        self._inv_dt = 1.0 / dt_s
        self._guard = guard
        # when the guard next measures this vehicle's clearance (never without a guard)
        self._check_at = _INF if guard is None else guard.check_at_s(k)

    def step(self, t_s: float) -> int:
        """Advance by one step ending at t_s; returns the bits of what happened."""
        px, py, pz = self.px, self.py, self.pz
        vx, vy, vz = self.vx, self.vy, self.vz
        gx, gy, gz = self._gx, self._gy, self._gz
        dt = self._dt
        ex, ey, ez = gx - px, gy - py, gz - pz
        d_xy = _hypot(ex, ey)
        active = self._active
        if active:
            dist = math.sqrt(d_xy * d_xy + ez * ez)
            inv = 1.0 / (dist if dist > 1e-9 else 1e-9)
            h = d_xy * inv
            w = abs(ez) * inv
            speed_xy, accel_xy, accel_z = self._speed_xy, self._accel_xy, self._accel_z
            vz_lim = self._climb if ez >= 0.0 else self._descent
            # along_line_limit for the speed and the acceleration
            if h > 0.0:
                speed_h, accel_h = speed_xy / h, accel_xy / h
            else:
                speed_h = accel_h = _INF
            if w > 0.0:
                speed_v, accel_v = vz_lim / w, accel_z / w
            else:
                speed_v = accel_v = _INF
            s_max = speed_v if speed_v < speed_h else speed_h
            if s_max == _INF:
                s_max = vz_lim if vz_lim < speed_xy else speed_xy
            a_eff = accel_v if accel_v < accel_h else accel_h
            if a_eff == _INF:
                a_eff = accel_z if accel_z < accel_xy else accel_xy
            speed = math.sqrt(2.0 * BRAKING_SHARE * a_eff * dist)
            if s_max < speed:
                speed = s_max
            reach = dist * self._inv_dt
            if reach < speed:
                speed = reach
            f = speed * inv
            dvx, dvy, dvz = ex * f - vx, ey * f - vy, ez * f - vz
            if dvx * dvx + dvy * dvy < self._dv_xy_max2_below:
                nvx, nvy = vx + dvx, vy + dvy  # within the limit: the scale would be >= 1
            else:
                dv_xy = _hypot(dvx, dvy)
                scale = self._dv_xy_max / (dv_xy if dv_xy > 1e-12 else 1e-12)
                if scale < 1.0:
                    nvx, nvy = vx + dvx * scale, vy + dvy * scale
                else:
                    nvx, nvy = vx + dvx, vy + dvy
            lim_z = self._dv_z_max
            nvz = vz + (-lim_z if dvz < -lim_z else lim_z if dvz > lim_z else dvz)
            wind = self._wind
            if wind is None:
                if not nvx * nvx + nvy * nvy < self._airspeed2_below:
                    air = _hypot(nvx, nvy)
                    if air > self._airspeed:
                        ratio = self._airspeed / air
                        nvx, nvy = nvx * ratio, nvy * ratio
            else:
                airx, airy = nvx - wind[0], nvy - wind[1]
                air = 0.0 if airx * airx + airy * airy < self._airspeed2_below else _hypot(
                    airx, airy)
                if air > self._airspeed:
                    ratio = self._airspeed / air
                    nvx, nvy = airx * ratio + wind[0], airy * ratio + wind[1]
        else:
            nvx = nvy = nvz = 0.0
        npx, npy, npz = px + nvx * dt, py + nvy * dt, pz + nvz * dt
        events = 0
        if npz < 0.0:
            npz = 0.0
            if nvz < 0.0:
                nvz = 0.0
            if self._landing:
                events = TOUCHED_DOWN
        if t_s >= self._check_at and active and abs(nvx) + abs(nvy) + abs(nvz) > 0.0:
            guard = self._guard
            assert guard is not None
            if guard(self.k, t_s, npx, npy, npz):
                npx, npy, npz = px, py, pz
                nvx = nvy = nvz = 0.0
                events |= OBSTACLE_STOP
            self._check_at = guard.check_at_s(self.k)
        inv_dt = self._inv_dt
        self.ax = ax = (nvx - vx) * inv_dt
        self.ay = ay = (nvy - vy) * inv_dt
        self.az = az = (nvz - vz) * inv_dt
        self.vx, self.vy, self.vz = nvx, nvy, nvz
        self.px, self.py, self.pz = npx, npy, npz
        # yaw: free (NaN goal) yaw follows the bearing to a position goal more than 2 m away
        goal_yaw, yaw = self._goal_yaw, self.yaw
        if goal_yaw == goal_yaw:
            desired = goal_yaw
        elif self._position and d_xy > 2.0:
            desired = _atan2(ex, ey) * DEG_PER_RAD
        else:
            desired = yaw
        if desired == yaw:
            diff = step = 0.0
        else:
            diff = (desired - yaw + 540.0) % 360.0 - 180.0
            if active:
                limit = self._yaw_step_max
                step = -limit if diff < -limit else limit if diff > limit else diff
                self.yaw = (yaw + step) % 360.0
            else:
                step = 0.0
        self.yaw_step = step
        if self.yaw_tracking and abs(diff - step) < YAW_REACHED_DEG:
            self.yaw_tracking = False
            events |= YAW_REACHED
        tracking = self.tracking
        if tracking != TRACK_NONE:
            ex, ey, ez = gx - npx, gy - npy, gz - npz
            dist2 = ex * ex + ey * ey + ez * ez
            if dist2 <= self._acceptance2 and (tracking == TRACK_PASS or (
                    tracking == TRACK_SETTLE and dist2 <= _SETTLED_GOAL2
                    and nvx * nvx + nvy * nvy + nvz * nvz <= _SETTLED_SPEED2)):
                self.tracking = TRACK_NONE
                events |= ARRIVED
        self.moving = moving = active and bool(nvx or nvy or nvz or self.yaw_tracking)
        rows = self._rows  # appended one by one: compiled, no tuple is built
        rows.append(npx)
        rows.append(npy)
        rows.append(npz)
        rows.append(self.yaw)
        rows.append(1.0 if moving else 0.0)
        if (-ACCEL_STEADY_M_S2 <= ax <= ACCEL_STEADY_M_S2
                and -ACCEL_STEADY_M_S2 <= ay <= ACCEL_STEADY_M_S2
                and -ACCEL_STEADY_M_S2 <= az <= ACCEL_STEADY_M_S2
                and -YAW_STEADY_DEG <= step <= YAW_STEADY_DEG and not self.yaw_tracking):
            events |= STEADY
        return events

    def store(self, dyn: FleetDynamics) -> None:
        """Write the vehicle's state back into its row of dyn (positions excepted: the fleet
        writes those with every other vehicle's)."""
        k = self.k
        dyn.velocity_m_s[k] = (self.vx, self.vy, self.vz)
        dyn.accel_m_s2[k] = (self.ax, self.ay, self.az)
        dyn.yaw_deg[k] = self.yaw
        dyn.tracking[k] = self.tracking
        dyn.yaw_tracking[k] = self.yaw_tracking


def _surely_below(limit: float) -> float:
    """A bound under limit**2: when x*x + y*y is below it, hypot(x, y) < limit for certain
    (the sum of squares and hypot are both within a few ulps of exact), so the hypot, a call
    out of compiled code, is needed only near or above the limit (then computed as before).
    -1.0 (no shortcut) for a limit under 1e-12, the floor of the step's division, or NaN."""
    return limit * limit * (1.0 - 1e-9) if limit >= 1e-12 else -1.0


def _state(dyn: FleetDynamics, k: int) -> list[float]:
    """Row k of dyn in the order of STATE_FIELDS."""
    p, v, a, g = (dyn.position_m[k].tolist(), dyn.velocity_m_s[k].tolist(),
                  dyn.accel_m_s2[k].tolist(), dyn.goal_m[k].tolist())
    return [p[0], p[1], p[2], v[0], v[1], v[2], a[0], a[1], a[2], float(dyn.yaw_deg[k]),
            float(dyn.tracking[k]), 1.0 if dyn.yaw_tracking[k] else 0.0, float(dyn.control[k]),
            g[0], g[1], g[2], float(dyn.goal_yaw_deg[k]), float(dyn.speed_xy_m_s[k]),
            float(dyn.accel_xy_m_s2[k]), float(dyn.accel_z_m_s2[k]), float(dyn.climb_m_s[k]),
            float(dyn.descent_m_s[k]), float(dyn.acceptance_m[k])]


def step_all(solos: list[SoloVehicle], t_s: float, bits: list[int]) -> int:
    """Step every vehicle of `solos` once (the step ending at t_s); bits[i] gets solos[i]'s
    result. Returns what happened to any of them, with STEADY only if every one is steady."""
    happened = 0
    steady = STEADY
    for i, solo in enumerate(solos):
        b = solo.step(t_s)
        bits[i] = b
        happened |= b
        steady &= b
    return (happened & ~STEADY) | steady


class SoloBattery(Protocol):
    """The fleet's batteries during a run of solo steps (emulator.flight.solo_battery)."""

    pct: list[float]  # every vehicle's charge after the last battery step

    def step(self, solos: list[SoloVehicle]) -> bool:
        """One battery step; whether the autopilots must look at the fleet after it."""


def run_solo_steps(solos: list[SoloVehicle], bits: list[int], steps: int, start: int,
                   dt_s: float, first_battery_step: int, battery_every: int,
                   battery: SoloBattery, charge: list[list[float]],
                   settle_steps: int) -> tuple[int, bool]:
    """Up to `steps` steps of `solos` from step `start` (emulator.flight.fleet's cruise):
    a battery step at step first_battery_step and every battery_every after it, the charges
    after each battery step appended to `charge`. Ends after a step in which something
    happened to a solo vehicle (bits[i]: solos[i]'s last step), or in which every one of them
    flies steadily again after speeding up, braking or turning (at settle_steps or later).
    Returns the steps run and whether the last one was a battery step."""
    settling = False
    battery_step = False
    battery_j = first_battery_step
    j = 0
    while j < steps:
        t_s = (start + j) * dt_s + dt_s  # a plain step's now_s + dt_s
        j += 1
        happened = step_all(solos, t_s, bits)
        battery_step = j == battery_j
        if battery_step:
            battery_j += battery_every
            if battery.step(solos):
                happened |= ARRIVED  # not an arrival: just stop here for the autopilots
            charge.append(battery.pct)
        if happened & SOLO_EVENTS:
            break
        if not happened & STEADY:
            settling = True
        elif settling and j >= settle_steps:
            break
    return j, battery_step
