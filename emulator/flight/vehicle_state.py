"""One vehicle's flight state: mode, landed state, the sequence phase and its goal bookkeeping.

The take-off, landing and return-to-launch sequences and the mission's positional items are
series of goals. `phase` names the step the current goal belongs to; when the physics reports
the goal reached, the autopilot advances the sequence from the phase (see
emulator.flight.sequences and emulator.flight.autopilot_mission). A timer works the same way:
`timer` names what happens when it fires. Nothing here acts: it is plain data, shared by the
autopilot and its parts without importing them.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from emulator.flight.modes import FlightMode, LandedState
from emulator.world import Blockage

__all__ = ["MISSION_PHASES", "Phase", "TimerAction", "VehicleState"]

Vec3 = tuple[float, float, float]


class Phase(Enum):
    """The step of a sequence the current goal belongs to: what its arrival starts."""

    IDLE = "idle"  # no sequence: on the ground, holding, or flying a goal that ends in a hold
    TAKING_OFF = "taking_off"  # TAKEOFF: vertical climb; arrival completes the take-off
    CLIMBING_TO_RTL = "climbing_to_rtl"  # RTL: climb to the return altitude, then return
    RETURNING = "returning"  # RTL: level flight home; arrival lands at `land_at_m`
    APPROACHING_LANDING = "approaching_landing"  # level flight to the point to land at
    DESCENDING = "descending"  # fast descent to MPC_LAND_ALT2, then the final descent
    LANDING = "landing"  # final descent at MPC_LAND_SPEED: ends at touchdown
    FALLING = "falling"  # a motor failed: coming down where it is, ends at touchdown
    MISSION_CLIMB = "mission_climb"  # mission start from the ground: climb, then the item
    MISSION_TAKEOFF = "mission_takeoff"  # a NAV_TAKEOFF item: reached, then the next item
    MISSION_WAYPOINT = "mission_waypoint"  # a NAV_WAYPOINT: reached, hold `item_wait_s`, next
    MISSION_LOITER = "mission_loiter"  # a NAV_LOITER_TIME: wait `item_wait_s`, reached, next
    MISSION_LOITER_UNLIMITED = "mission_loiter_unlimited"  # NAV_LOITER_UNLIM: reached, stay


MISSION_PHASES = frozenset({
    Phase.MISSION_CLIMB, Phase.MISSION_TAKEOFF, Phase.MISSION_WAYPOINT, Phase.MISSION_LOITER,
    Phase.MISSION_LOITER_UNLIMITED,
})


class TimerAction(Enum):
    """What the vehicle's timer (the fleet's `timer_s`) does when it fires."""

    NONE = "none"
    AUTO_DISARM = "auto_disarm"  # COM_DISARM_LAND after touchdown
    PREFLIGHT_DISARM = "preflight_disarm"  # COM_DISARM_PRFLT after arming without take-off
    MISSION_NEXT = "mission_next"  # a mission hold or delay ended: item `timer_seq` + 1
    MISSION_REACHED_NEXT = "mission_reached_next"  # a loiter ended: item `timer_seq` reached


@dataclass(slots=True)
class VehicleState:
    """Everything the autopilot of one vehicle holds between physics steps.

    The fleet's arrays hold the rest (position, velocity, goal, armed, airborne, battery).
    """

    home_m: Vec3
    mode: FlightMode = FlightMode.HOLD
    landed_state: LandedState = LandedState.ON_GROUND
    phase: Phase = Phase.IDLE
    land_at_m: tuple[float, float] | None = None  # RETURNING: where the return ends
    item_seq: int = 0  # mission phases: the item the goal belongs to
    item_wait_s: float = 0.0  # MISSION_WAYPOINT / MISSION_LOITER: the wait at the item
    blockage: Blockage | None = None  # the goal was cut short before this obstacle
    goal_pending: bool = False  # a goal whose end the physics has not reported yet
    timer: TimerAction = TimerAction.NONE
    timer_seq: int = 0  # MISSION_NEXT / MISSION_REACHED_NEXT: the item the wait belongs to
    timer_busy: bool = False  # the timer counts as work in progress (not a preflight timeout)
    speed_override_m_s: float | None = None  # DO_CHANGE_SPEED's horizontal speed
    photo_count: int = 0
