"""The take-off, landing and return-to-launch sequences, step by step.

Each sequence is a series of goals; the vehicle's `state.phase` names the step its current
goal belongs to. A command or a failsafe starts a sequence here; when the physics reports the
goal reached, `advance` starts the next step from the phase:

- take-off: TAKING_OFF (vertical climb) -> take-off complete, HOLD;
- landing: [APPROACHING_LANDING (level flight to the point)] -> [DESCENDING (fast, to
  MPC_LAND_ALT2)] -> LANDING (MPC_LAND_SPEED until touchdown);
- return to launch: [CLIMBING_TO_RTL (to RTL_RETURN_ALT)] -> RETURNING (level, home) -> the
  landing sequence at home.

A goal cut short by an obstacle ends its sequence (the vehicle holds there).
"""

from __future__ import annotations

import math

from emulator.flight import dynamics as dy
from emulator.flight.limits import check_altitude, check_distance_from_home
from emulator.flight.modes import FlightMode, LandedState
from emulator.flight.refusal import CommandRefused
from emulator.flight.vehicle_control import VehicleControl
from emulator.flight.vehicle_state import Phase
from emulator.truth_events import TruthEventKind

__all__ = [
    "GROUND_GOAL_Z_M", "advance", "begin_climb", "descend_and_land", "land",
    "require_air", "return_to_launch", "start_land", "start_rtl", "takeoff",
]

Vec3 = tuple[float, float, float]
GROUND_GOAL_Z_M = -1.0  # landing descends towards a goal below ground until touchdown


def require_air(ap: VehicleControl, what: str) -> None:
    if not ap.in_air:
        raise CommandRefused(f"{what} refused: vehicle is on the ground")


def advance(ap: VehicleControl, phase: Phase, land_at_m: tuple[float, float] | None) -> None:
    """The goal of `phase` was reached: start the sequence's next step. `land_at_m` is the
    landing point the goal carried (RETURNING)."""
    if phase is Phase.TAKING_OFF:
        _takeoff_complete(ap)
    elif phase is Phase.CLIMBING_TO_RTL:
        _return_home(ap)
    elif phase is Phase.RETURNING:
        descend_and_land(ap, land_at_m)
    elif phase is Phase.APPROACHING_LANDING:
        descend_and_land(ap, None)
    elif phase is Phase.DESCENDING:
        _final_descent(ap)
    # IDLE, LANDING and FALLING end by holding or at touchdown: nothing follows


# ----------------------------------------------------------------- take-off
def takeoff(ap: VehicleControl, altitude_m: float | None) -> None:
    if not ap.armed:
        raise CommandRefused("Takeoff refused: arm first")
    if ap.in_air:
        raise CommandRefused("Takeoff refused: already in the air")
    if altitude_m is None or math.isnan(altitude_m):
        altitude_m = ap.params["MIS_TAKEOFF_ALT"]
    x, y, z = ap.position_m
    home = ap.state.home_m
    target = (x, y, home[2] + altitude_m)
    check_altitude(ap.params, home, target[2], "Takeoff")
    if target[2] <= z + 0.5:
        raise CommandRefused(f"Takeoff refused: altitude {altitude_m:.1f} m too low")
    ap.switch_mode(FlightMode.TAKEOFF)
    begin_climb(ap, target, Phase.TAKING_OFF)


def begin_climb(ap: VehicleControl, target_m: Vec3, phase: Phase) -> None:
    """Leave the ground and climb vertically to target_m; `phase` is what the climb is for."""
    ap.cancel_timer()
    ap.fleet.airborne[ap.k] = True
    ap.update_charging()
    ap.event(TruthEventKind.TAKEOFF, altitude_m=target_m[2])
    ap.fly_to(target_m, phase=phase, climb_m_s=ap.params["MPC_TKO_SPEED"])
    ap.state.landed_state = LandedState.TAKEOFF


def _takeoff_complete(ap: VehicleControl) -> None:
    ap.state.landed_state = LandedState.IN_AIR
    ap.event(TruthEventKind.TAKEOFF_COMPLETE, position_m=list(ap.position_m))
    ap.listener.on_state_changed()
    ap.switch_mode(FlightMode.HOLD)


# ------------------------------------------------------------------ landing
def land(ap: VehicleControl, at_m: tuple[float, float] | None) -> None:
    require_air(ap, "Land")
    if at_m is not None:
        check_distance_from_home(ap.params, ap.state.home_m, at_m[0], at_m[1], "Land")
    start_land(ap, at_m)


def start_land(ap: VehicleControl, at_m: tuple[float, float] | None) -> None:
    """LAND mode (a command or a failsafe): land at at_m, or where the vehicle is."""
    ap.pause_mission()
    ap.switch_mode(FlightMode.LAND)
    descend_and_land(ap, at_m)


def descend_and_land(ap: VehicleControl, at_m: tuple[float, float] | None) -> None:
    """Fly level to at_m (if given and not there), descend, then land slowly."""
    x, y, z = ap.position_m
    if at_m is not None and math.hypot(at_m[0] - x, at_m[1] - y) > 0.5:
        ap.fly_to((at_m[0], at_m[1], z), phase=Phase.APPROACHING_LANDING)
        return
    slow_alt = ap.params["MPC_LAND_ALT2"]
    if z > slow_alt + 0.5:
        ap.fly_to((x, y, slow_alt), phase=Phase.DESCENDING, tracking=dy.TRACK_PASS)
    else:
        _final_descent(ap)


def _final_descent(ap: VehicleControl) -> None:
    x, y, _ = ap.position_m
    ap.fly_to((x, y, GROUND_GOAL_Z_M), phase=Phase.LANDING, tracking=dy.TRACK_NONE,
              descent_m_s=ap.params["MPC_LAND_SPEED"])
    ap.state.landed_state = LandedState.LANDING


# ------------------------------------------------------------------- return
def return_to_launch(ap: VehicleControl) -> None:
    require_air(ap, "Return to launch")
    start_rtl(ap)


def start_rtl(ap: VehicleControl) -> None:
    """RTL mode (a command, a mission item or a failsafe): climb, fly home, land."""
    ap.pause_mission()
    ap.switch_mode(FlightMode.RTL)
    x, y, z = ap.position_m
    hx, hy, _ = ap.rtl_destination_m()
    hz = ap.state.home_m[2]
    if math.hypot(hx - x, hy - y) < ap.params["NAV_ACC_RAD"]:
        descend_and_land(ap, (hx, hy))
        return
    return_alt = max(z, hz + ap.params["RTL_RETURN_ALT"])
    if return_alt > z + 0.5:
        ap.fly_to((x, y, return_alt), phase=Phase.CLIMBING_TO_RTL)
    else:
        _return_home(ap)


def _return_home(ap: VehicleControl) -> None:
    hx, hy, _ = ap.rtl_destination_m()
    ap.fly_to((hx, hy, ap.position_m[2]), phase=Phase.RETURNING)
    ap.state.land_at_m = (hx, hy)
