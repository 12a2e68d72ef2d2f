"""Operator resets: what a benchmark operator does between tasks, never flight.

These move a vehicle or refill its battery directly, outside the flight model, so each one is
recorded as an `operator_*` truth event and is reachable only through the operator services.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from emulator.flight import dynamics as dy
from emulator.flight.modes import FlightMode, LandedState
from emulator.truth_events import TruthEventKind
from mavlink_vocabulary import FailuresCleared

if TYPE_CHECKING:
    from emulator.flight.autopilot import Autopilot

__all__ = ["place_on_ground", "set_battery"]


def place_on_ground(ap: Autopilot, x_m: float, y_m: float, heading_deg: float | None = None
                    ) -> None:
    """Put the vehicle disarmed on the ground at (x, y), at rest, in HOLD."""
    fleet, k, dyn = ap.fleet, ap.k, ap.fleet.dyn
    ap.mission.pause()
    ap.cancel_timer()
    ap.drop_goal()
    dyn.position_m[k] = (x_m, y_m, 0.0)
    dyn.goal_m[k] = (x_m, y_m, 0.0)
    dyn.velocity_m_s[k] = 0.0
    dyn.accel_m_s2[k] = 0.0
    dyn.control[k] = dy.CONTROL_NONE
    dyn.tracking[k] = dy.TRACK_NONE
    dyn.yaw_tracking[k] = False
    if heading_deg is not None:
        dyn.yaw_deg[k] = heading_deg % 360.0
    fleet.armed[k] = False
    fleet.airborne[k] = False
    fleet.guard.forget(k)
    ap.landed_state = LandedState.ON_GROUND
    ap.mode = FlightMode.HOLD
    repaired = ap.failures.any
    if repaired:
        ap.event(TruthEventKind.OPERATOR_REPAIR,
                 failures=[name for name in ("gps", "motor", "mavlink")
                           if getattr(ap.failures, f"{name}_off")])
    ap.failures.clear()
    if repaired:
        ap.announce(FailuresCleared())
    ap.event(TruthEventKind.OPERATOR_PLACE, position_m=[x_m, y_m, 0.0])
    ap.update_charging()
    ap.listener.on_operator_reset()


def set_battery(ap: Autopilot, pct: float) -> None:
    """Set the charge level (percent, 0-100)."""
    if not 0.0 <= pct <= 100.0:
        raise ValueError(f"battery level must be within [0, 100] %, got {pct}")
    bat = ap.fleet.bat
    bat.pct[ap.k] = pct
    bat.level[ap.k] = 0
    bat.step(0.0, ap.fleet.airborne, ap.fleet.armed,
             ap.fleet.dyn.airspeed_m_s(), ap.fleet.dyn.velocity_m_s[:, 2])
    ap.event(TruthEventKind.OPERATOR_BATTERY, battery_pct=pct)
    ap.update_charging()
    ap.listener.on_operator_reset()
