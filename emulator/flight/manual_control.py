"""Manual flight (PX4's POSCTL and ALTCTL) from joystick input (MAVLink MANUAL_CONTROL).

There is no RC transmitter: the joystick a ground station sends over MAVLink (QGroundControl's
virtual joystick, MAVSDK's manual_control plugin) is the only stick input, taken when
COM_RC_IN_MODE allows a joystick (1, 2 or 3; 0 is RC only and 4 disables stick input).
Sticks are normalised: pitch forward, roll right and yaw clockwise in [-1, 1], throttle in
[-1, 1] with the centre 0 (MANUAL_CONTROL's z of 500); a deadzone of MPC_HOLD_DZ around the
centre reads as centred.

- POSCTL: pitch and roll set the horizontal velocity in the body frame (MPC_VEL_MANUAL at full
  stick); centred sticks hold the position.
- ALTCTL: pitch and roll tilt the vehicle (MPC_MAN_TILT_MAX at full stick), which accelerates
  it by g * tan(tilt); level, it drifts and air drag slows it.
- Both: the throttle sets the climb or sink rate (MPC_Z_VEL_MAX_UP / _DN at full stick;
  centred holds the altitude) and the yaw stick the yaw rate (MPC_MAN_Y_MAX). On the ground,
  armed, a throttle above the centre takes off; flown down to the ground, the vehicle lands
  (landing detected, disarm after COM_DISARM_LAND).

Entering either mode needs input received within COM_RC_LOSS_T (wall seconds: a link rule,
as offboard's); when input stops for that long in the air, NAV_RCL_ACT acts once.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from emulator.flight import dynamics as dy
from emulator.flight.attitude_control import attitude_acceleration_enu
from emulator.flight.failures import DLL_ACTIONS
from emulator.flight.modes import FlightMode
from emulator.flight.offboard_frames import body_to_enu
from emulator.flight.refusal import CommandRefused
from emulator.flight.vehicle_control import VehicleControl
from emulator.truth_events import TruthEventKind
from mavlink_vocabulary import FailsafeAction, ManualControlLost

__all__ = ["JOYSTICK_RC_IN_MODES", "MANUAL_MODES", "ManualControl", "Sticks"]

MANUAL_MODES = frozenset({FlightMode.POSCTL, FlightMode.ALTCTL})
JOYSTICK_RC_IN_MODES = frozenset({1, 2, 3})  # COM_RC_IN_MODE values that take a joystick
ALTCTL_DRAG_1_S = 0.5  # the horizontal deceleration per m/s of a level vehicle in ALTCTL
RISING_M_S = 0.1  # a climb rate above this takes off


class Sticks(NamedTuple):
    """One joystick reading, every axis in [-1, 1] (throttle: 0 is the centre)."""

    pitch: float  # forward
    roll: float  # right
    throttle: float  # up
    yaw: float  # clockwise


CENTRED = Sticks(0.0, 0.0, 0.0, 0.0)


def _deadzone(value: float, zone: float) -> float:
    """The stick beyond the deadzone, rescaled to [-1, 1]."""
    if abs(value) <= zone:
        return 0.0
    return math.copysign((abs(value) - zone) / (1.0 - zone), value)


class ManualControl:
    """The latest stick input of one vehicle and its flight in POSCTL or ALTCTL."""

    def __init__(self, autopilot: VehicleControl) -> None:
        self.ap = autopilot
        self._sticks: Sticks | None = None
        self._received_wall_s = -math.inf
        self._lost = False

    @property
    def active(self) -> bool:
        return self.ap.state.mode in MANUAL_MODES

    @property
    def sticks(self) -> Sticks | None:
        return self._sticks

    def takes_joystick(self) -> bool:
        return int(self.ap.params["COM_RC_IN_MODE"]) in JOYSTICK_RC_IN_MODES

    def input(self, sticks: Sticks, wall_now_s: float) -> None:
        """A joystick reading. Raises CommandRefused (nothing changes) when COM_RC_IN_MODE
        takes no joystick."""
        if not self.takes_joystick():
            raise CommandRefused(f"Joystick ignored: COM_RC_IN_MODE "
                                 f"{int(self.ap.params['COM_RC_IN_MODE'])}")
        self._sticks = sticks
        self._received_wall_s = wall_now_s
        self._lost = False
        if self.active:
            self.apply()

    def enter(self, mode: FlightMode, wall_now_s: float) -> None:
        ap = self.ap
        if not self.takes_joystick():
            raise CommandRefused(f"Mode {mode.label} refused: no joystick, COM_RC_IN_MODE "
                                 f"{int(ap.params['COM_RC_IN_MODE'])}")
        if wall_now_s - self._received_wall_s > ap.params["COM_RC_LOSS_T"]:
            raise CommandRefused(f"Mode {mode.label} refused: no manual control input")
        ap.pause_mission()
        ap.switch_mode(mode)
        self.apply()

    def _climb_m_s(self, sticks: Sticks) -> float:
        p = self.ap.params
        up = _deadzone(sticks.throttle, p["MPC_HOLD_DZ"])
        return up * (p["MPC_Z_VEL_MAX_UP"] if up > 0.0 else p["MPC_Z_VEL_MAX_DN"])

    def apply(self) -> None:
        """Fly the sticks: by velocity from now on (on the ground, only a raised throttle
        takes off)."""
        ap = self.ap
        sticks = self._sticks or CENTRED
        if not ap.armed:
            return
        if not ap.in_air:
            if self._climb_m_s(sticks) <= RISING_M_S:
                return
            ap.lift_off(None)
        dyn, k = ap.fleet.dyn, ap.k
        if dyn.control[k] != dy.CONTROL_VELOCITY:
            ap.drop_goal()
            dyn.control[k] = dy.CONTROL_VELOCITY
            dyn.tracking[k] = dy.TRACK_NONE
            dyn.velocity_sp_m_s[k] = dyn.velocity_m_s[k]
            ap.refresh_busy()
        self.on_step(0.0)

    def on_step(self, dt_s: float) -> None:
        """The velocity and heading set-points for the next physics step."""
        ap = self.ap
        dyn, k, p = ap.fleet.dyn, ap.k, ap.params
        sticks = self._sticks or CENTRED
        zone = p["MPC_HOLD_DZ"]
        forward, right = _deadzone(sticks.pitch, zone), _deadzone(sticks.roll, zone)
        yaw_deg = float(dyn.yaw_deg[k])
        limit = p["MPC_XY_VEL_MAX"]
        if ap.state.mode is FlightMode.ALTCTL:
            tilt = p["MPC_MAN_TILT_MAX"]
            hover = p["MPC_THR_HOVER"]
            ax, ay, _ = attitude_acceleration_enu(right * tilt, -forward * tilt, yaw_deg,
                                                  hover, hover)
            vx, vy, _ = (float(v) for v in dyn.velocity_sp_m_s[k])
            vx += (ax - ALTCTL_DRAG_1_S * vx) * dt_s
            vy += (ay - ALTCTL_DRAG_1_S * vy) * dt_s
        else:
            speed = min(p["MPC_VEL_MANUAL"], limit)
            vx, vy = body_to_enu(yaw_deg, forward * speed, right * speed)
        horizontal = math.hypot(vx, vy)
        if horizontal > limit:
            vx, vy = vx * limit / horizontal, vy * limit / horizontal
        dyn.velocity_sp_m_s[k] = (vx, vy, self._climb_m_s(sticks))
        rate = _deadzone(sticks.yaw, zone) * p["MPC_MAN_Y_MAX"]
        dyn.yaw_rate_deg_s[k] = max(abs(rate), p["MPC_YAWRAUTO_MAX"])
        # the heading the next physics step turns to (apply() runs between steps: dt_s 0)
        dyn.goal_yaw_deg[k] = (yaw_deg + rate * ap.fleet.dt_s) % 360.0

    def check_link(self, wall_now_s: float) -> None:
        """Manual control loss: no input for COM_RC_LOSS_T in POSCTL/ALTCTL, in the air."""
        ap = self.ap
        if self._lost or not self.active or not ap.in_air:
            return
        timeout_s = ap.params["COM_RC_LOSS_T"]
        if wall_now_s - self._received_wall_s <= timeout_s:
            return
        self._lost = True
        self._sticks = CENTRED
        action = DLL_ACTIONS.get(int(ap.params["NAV_RCL_ACT"]))
        ap.event(TruthEventKind.FAILSAFE, reason="manual_control_lost", action=action or "none")
        ap.announce(ManualControlLost(FailsafeAction(action) if action else None))
        if action == "hold":
            ap.hold()
        elif action == "return":
            ap.start_rtl()
        elif action == "land":
            ap.start_land(None)
