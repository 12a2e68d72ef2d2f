"""One vehicle of a fleet as its autopilot drives it: state, parameters, goals, timer, events.

`Vehicle` is the lower half of the autopilot (emulator.flight.autopilot.Autopilot adds the
flight logic: commands, sequences, reactions to the physics). It never moves the vehicle
itself: it sets goals (a position to fly to, a yaw) in the fleet's arrays and the vectorised
dynamics fly them; collision prevention may cut a goal short before an obstacle.
"""

from __future__ import annotations

import math

from emulator.flight import dynamics as dy
from emulator.flight.fleet_view import FleetView
from emulator.flight.limits import check_target
from emulator.flight.listener import AutopilotListener, SilentListener
from emulator.flight.modes import FlightMode, LandedState
from emulator.flight.params import ParamStore
from emulator.flight.vehicle_state import Phase, TimerAction, VehicleState
from emulator.geo import wrap_heading_deg
from emulator.networks import system_id
from emulator.scenario import VehicleSpec
from emulator.truth_events import TruthEventKind
from mavlink_vocabulary import Announcement, build_statustext

__all__ = ["Vehicle"]

Vec3 = tuple[float, float, float]


class Vehicle:
    """Vehicle `k` of a fleet: its state, parameters and goals."""

    def __init__(self, k: int, spec: VehicleSpec, fleet: FleetView) -> None:
        self.k = k
        self.system_id = system_id(k)  # MAVLink: network k // 250 (emulator.networks)
        self.vehicle_id = spec.id
        self.spec = spec
        self.fleet = fleet
        self.listener: AutopilotListener = SilentListener()
        self.params = ParamStore({
            "MPC_XY_VEL_MAX": spec.max_speed_m_s,
            "MPC_XY_CRUISE": min(8.0, spec.max_speed_m_s),
            "GF_MAX_VER_DIST": spec.max_altitude_m,
            "SIM_SENS_RAD": spec.perceived_radius_m,
            "SIM_TASK_RAD": spec.task_radius_m,
            "BAT_CAPACITY": spec.battery_capacity_mah,
            "MAV_SYS_ID": system_id(k),
        })
        self.state = VehicleState(home_m=spec.home_m)
        dyn = fleet.dyn
        dyn.position_m[k] = spec.position_m
        dyn.yaw_deg[k] = wrap_heading_deg(spec.heading_deg)
        fleet.bat.pct[k] = spec.battery_pct
        self.apply_params()
        if spec.position_m[2] > 0.0:  # spawned in the air: armed and holding
            fleet.armed[k] = fleet.airborne[k] = True
            self.state.landed_state = LandedState.IN_AIR
            self._set_goal(spec.position_m, dy.TRACK_NONE)
        self.update_charging()

    # ------------------------------------------------------------------ state
    @property
    def mode(self) -> FlightMode:
        return self.state.mode

    @mode.setter
    def mode(self, mode: FlightMode) -> None:
        """Set the mode silently (an operator reset); `switch_mode` records and announces."""
        self.state.mode = mode

    @property
    def landed_state(self) -> LandedState:
        return self.state.landed_state

    @landed_state.setter
    def landed_state(self, landed_state: LandedState) -> None:
        self.state.landed_state = landed_state

    @property
    def home_m(self) -> Vec3:
        return self.state.home_m

    @home_m.setter
    def home_m(self, home_m: Vec3) -> None:
        """Move home without the geofence checks of `set_home` (an operator reset)."""
        self.state.home_m = home_m

    @property
    def phase(self) -> Phase:
        return self.state.phase

    @property
    def photo_count(self) -> int:
        return self.state.photo_count

    @property
    def speed_override_m_s(self) -> float | None:
        return self.state.speed_override_m_s

    @property
    def armed(self) -> bool:
        return bool(self.fleet.armed[self.k])

    @property
    def in_air(self) -> bool:
        return bool(self.fleet.airborne[self.k])

    @property
    def position_m(self) -> Vec3:
        p = self.fleet.dyn.position_m[self.k]
        return float(p[0]), float(p[1]), float(p[2])

    @property
    def battery_pct(self) -> float:
        return float(self.fleet.bat.pct[self.k])

    @property
    def now_s(self) -> float:
        return self.fleet.now_s

    def apply_params(self) -> None:
        """Push parameter values into the fleet's limit arrays."""
        p, k, dyn, bat = self.params, self.k, self.fleet.dyn, self.fleet.bat
        cruise = self.state.speed_override_m_s or p["MPC_XY_CRUISE"]
        dyn.speed_xy_m_s[k] = min(cruise, p["MPC_XY_VEL_MAX"])
        dyn.airspeed_max_m_s[k] = p["MPC_XY_VEL_MAX"]
        dyn.climb_m_s[k] = p["MPC_Z_VEL_MAX_UP"]
        dyn.descent_m_s[k] = p["MPC_Z_VEL_MAX_DN"]
        dyn.accel_xy_m_s2[k] = p["MPC_ACC_HOR"]
        dyn.accel_z_m_s2[k] = p["MPC_ACC_UP_MAX"]
        dyn.yaw_rate_deg_s[k] = p["MPC_YAWRAUTO_MAX"]
        dyn.acceptance_m[k] = p["NAV_ACC_RAD"]
        bat.low_pct[k] = 100.0 * p["BAT_LOW_THR"]
        bat.critical_pct[k] = 100.0 * p["BAT_CRIT_THR"]
        bat.emergency_pct[k] = 100.0 * p["BAT_EMERGEN_THR"]
        bat.hover_endurance_s[k] = p["SIM_HOVER_ENDUR"]

    def set_param(self, name: str, value: float) -> float:
        before = self.params[name]
        stored = self.params.set(name, value)
        if stored != before:  # the same value again (a retransmitted PARAM_SET) changes nothing
            self.apply_params()
        return stored

    def event(self, kind: TruthEventKind, **data: object) -> None:
        """Record a ground-truth event; a failsafe also ends the vehicle's goal."""
        self.fleet.recorder.record_event(self.now_s, self.vehicle_id, kind, **data)
        if kind is TruthEventKind.FAILSAFE:
            self.fleet.mark_ended(self.k)

    def say(self, severity: int, text: str) -> None:
        self.listener.on_statustext(severity, text)

    def announce(self, message: Announcement) -> None:
        """Send one of the vocabulary's STATUSTEXT messages, with its severity."""
        self.say(message.severity, build_statustext(message))

    def switch_mode(self, mode: FlightMode) -> None:
        """Enter `mode`, recorded and announced; nothing else changes."""
        st = self.state
        if mode is not st.mode:
            self.event(TruthEventKind.MODE, previous=st.mode.label, mode=mode.label)
            st.mode = mode
            self.listener.on_state_changed()

    def refresh_busy(self) -> None:
        """The fleet's `busy` flag: a goal, a yaw, a busy timer or charging in progress."""
        k, f, st = self.k, self.fleet, self.state
        f.busy[k] = (
            st.goal_pending or bool(f.dyn.yaw_tracking[k]) or st.timer_busy
            or (f.bat.charge_rate_pct_s[k] > 0.0 and f.bat.pct[k] < 100.0)
        )

    def set_timer(self, delay_s: float, action: TimerAction, *, busy: bool,
                  seq: int = 0) -> None:
        """`action` after delay_s of simulated time (one timer: it replaces any other)."""
        st = self.state
        self.fleet.timer_s[self.k] = self.now_s + delay_s
        st.timer, st.timer_seq, st.timer_busy = action, seq, busy
        self.refresh_busy()

    def cancel_timer(self) -> None:
        self.fleet.timer_s[self.k] = math.inf
        self.state.timer = TimerAction.NONE
        self.state.timer_busy = False

    def check_target(self, target_m: Vec3, what: str) -> None:
        """Refuse a destination outside the geofence (ceiling, distance from home)."""
        check_target(self.params, self.home_m, target_m, what)

    # ------------------------------------------------------------------ goals
    def _set_goal(self, goal_m: Vec3, tracking: int, *, yaw_deg: float = math.nan) -> None:
        dyn, k = self.fleet.dyn, self.k
        dyn.control[k] = dy.CONTROL_POSITION
        dyn.goal_m[k] = goal_m
        dyn.tracking[k] = tracking
        dyn.goal_yaw_deg[k] = yaw_deg
        self.state.goal_pending = tracking != dy.TRACK_NONE
        self.refresh_busy()

    def drop_goal(self) -> None:
        """Forget the current goal's sequence step, blockage and pending end."""
        st = self.state
        st.phase = Phase.IDLE
        st.blockage = None
        st.goal_pending = False

    def fly_to(
        self, target_m: Vec3, *, phase: Phase = Phase.IDLE,
        tracking: int = dy.TRACK_SETTLE, speed_m_s: float | None = None,
        climb_m_s: float | None = None, descent_m_s: float | None = None,
        yaw_deg: float = math.nan,
    ) -> None:
        """Fly the straight line to target_m as step `phase` of a sequence; collision
        prevention may stop it short (which ends the sequence)."""
        self.apply_params()
        dyn, k = self.fleet.dyn, self.k
        if speed_m_s is not None:
            dyn.speed_xy_m_s[k] = min(speed_m_s, self.params["MPC_XY_VEL_MAX"])
        if climb_m_s is not None:
            dyn.climb_m_s[k] = climb_m_s
        if descent_m_s is not None:
            dyn.descent_m_s[k] = descent_m_s
        st = self.state
        if self.in_air:  # any new goal ends a take-off climb or a final descent
            st.landed_state = LandedState.IN_AIR
        blockage = self.fleet.world.first_blockage(self.position_m, target_m)
        st.blockage = blockage
        st.phase = phase
        if blockage is not None:
            self._set_goal(blockage.stop_m, dy.TRACK_SETTLE, yaw_deg=yaw_deg)
        else:
            self._set_goal(target_m, tracking, yaw_deg=yaw_deg)
            if tracking == dy.TRACK_NONE:
                st.goal_pending = True  # reported by touchdown instead
                self.refresh_busy()

    def lift_off(self, altitude_m: float | None) -> None:
        """Leave the ground under direct control (offboard, sticks): airborne from now on."""
        self.fleet.airborne[self.k] = True
        self.state.landed_state = LandedState.IN_AIR
        self.cancel_timer()
        self.update_charging()
        self.event(TruthEventKind.TAKEOFF, altitude_m=altitude_m)

    def brake_and_hold(self) -> None:
        """Stop where braking ends (PX4's hold) and stay there."""
        dyn, k = self.fleet.dyn, self.k
        if not self.in_air:
            return
        vel = dyn.velocity_m_s[k]
        stop = dyn.position_m[k].copy()
        stop[:2] += vel[:2] * math.hypot(vel[0], vel[1]) / (2.0 * dyn.accel_xy_m_s2[k])
        stop[2] += vel[2] * abs(vel[2]) / (2.0 * dyn.accel_z_m_s2[k])
        stop[2] = max(stop[2], 0.5)
        self.fly_to((float(stop[0]), float(stop[1]), float(stop[2])),
                    yaw_deg=float(dyn.yaw_deg[k]))

    def hold_position(self) -> None:
        """Hold where the vehicle is (no braking); any sequence ends."""
        self.state.phase = Phase.IDLE
        self.state.blockage = None
        self._set_goal(self.position_m, dy.TRACK_NONE)

    # ---------------------------------------------------------------- charging
    def update_charging(self) -> None:
        """Charge on the ground, disarmed, at a charging station; nowhere else."""
        f, k = self.fleet, self.k
        rate = 0.0
        if not self.armed and not self.in_air:
            x, y, _ = self.position_m
            station = f.world.charging_station_at(x, y)
            if station is not None and station.charge_rate_pct_s:
                rate = station.charge_rate_pct_s
        was = f.bat.charge_rate_pct_s[k]
        f.bat.charge_rate_pct_s[k] = rate
        if rate > 0.0 and was == 0.0 and self.battery_pct < 100.0:
            self.event(TruthEventKind.CHARGING, battery_pct=self.battery_pct)
        self.refresh_busy()
