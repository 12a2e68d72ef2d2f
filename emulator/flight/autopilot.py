"""One vehicle's PX4-like flight logic: arming, modes, goals and failsafes.

The autopilot never moves its vehicle itself: it sets goals (a position to fly to, a
velocity, a yaw) in the fleet's arrays and the vectorised dynamics fly them. It reacts to
what the physics reports (arrived, touched down, stopped by an obstacle, battery level,
timers). Commands that cannot be carried out raise :class:`CommandRefused` before anything
changes.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

from emulator.flight import dynamics as dy
from emulator.flight.autopilot_mission import MissionRunner
from emulator.flight.battery import BATTERY_CRITICAL, BATTERY_EMERGENCY, BATTERY_LOW
from emulator.flight.camera import ImageCapture, capture_image
from emulator.flight.failures import VehicleFailures
from emulator.flight.limits import (
    SpeedKind,
    check_altitude,
    check_distance_from_home,
    check_home,
    check_speed,
    check_target,
    check_yaw_rate,
)
from emulator.flight.listener import AutopilotListener, SilentListener
from emulator.flight.modes import FlightMode, LandedState
from emulator.flight.offboard import OffboardControl
from emulator.flight.params import ParamStore
from emulator.flight.refusal import CommandRefused, Severity
from emulator.geo import wrap_heading_deg
from emulator.scenario import VehicleSpec
from emulator.world import Blockage

if TYPE_CHECKING:
    from emulator.flight.fleet import Fleet

__all__ = ["Autopilot", "AutopilotListener", "CommandRefused", "ImageCapture", "Severity"]

Vec3 = tuple[float, float, float]
GROUND_GOAL_Z_M = -1.0  # landing descends towards a goal below ground until touchdown


class Autopilot:
    """Flight logic of vehicle `k` of a fleet."""

    def __init__(self, k: int, spec: VehicleSpec, fleet: Fleet) -> None:
        self.k = k
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
            "MAV_SYS_ID": k + 1,
        })
        self.mode = FlightMode.HOLD
        self.home_m: Vec3 = spec.home_m
        self.landed_state = LandedState.ON_GROUND
        self.speed_override_m_s: float | None = None
        self.photo_count = 0
        self.mission = MissionRunner(self)
        self._on_arrive: Callable[[], None] | None = None
        self._blockage: Blockage | None = None
        self._goal_pending = False
        self._timer_action: Callable[[], None] | None = None
        self._timer_busy = False
        self.offboard = OffboardControl(self)
        self.failures = VehicleFailures(self)
        dyn = fleet.dyn
        dyn.position_m[k] = spec.position_m
        dyn.yaw_deg[k] = wrap_heading_deg(spec.heading_deg)
        fleet.bat.pct[k] = spec.battery_pct
        self.apply_params()
        if spec.position_m[2] > 0.0:  # spawned in the air: armed and holding
            fleet.armed[k] = fleet.airborne[k] = True
            self.landed_state = LandedState.IN_AIR
            self._set_goal(spec.position_m, dy.TRACK_NONE)
        self._update_charging()

    # ------------------------------------------------------------------ state
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
        cruise = self.speed_override_m_s or p["MPC_XY_CRUISE"]
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

    def _event(self, kind: str, **data: object) -> None:
        self.fleet.recorder.record_event(self.now_s, self.vehicle_id, kind, **data)
        if kind == "failsafe":
            self.fleet.mark_ended(self.k)

    def _say(self, severity: int, text: str) -> None:
        self.listener.on_statustext(severity, text)

    def _set_mode(self, mode: FlightMode) -> None:
        if mode is not self.mode:
            self._event("mode", previous=self.mode.label, mode=mode.label)
            self.mode = mode
            self.listener.on_state_changed()

    def _refresh_busy(self) -> None:
        k, f = self.k, self.fleet
        f.busy[k] = (
            self._goal_pending or bool(f.dyn.yaw_tracking[k]) or self._timer_busy
            or (f.bat.charge_rate_pct_s[k] > 0.0 and f.bat.pct[k] < 100.0)
        )

    def _set_timer(self, delay_s: float, action: Callable[[], None], *, busy: bool) -> None:
        self.fleet.timer_s[self.k] = self.now_s + delay_s
        self._timer_action = action
        self._timer_busy = busy
        self._refresh_busy()

    def _cancel_timer(self) -> None:
        self.fleet.timer_s[self.k] = math.inf
        self._timer_action = None
        self._timer_busy = False

    def _require_air(self, what: str) -> None:
        if not self.in_air:
            raise CommandRefused(f"{what} refused: vehicle is on the ground")

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
        self._goal_pending = tracking != dy.TRACK_NONE
        self._refresh_busy()

    def fly_to(
        self, target_m: Vec3, *, then: Callable[[], None] | None = None,
        tracking: int = dy.TRACK_SETTLE, speed_m_s: float | None = None,
        climb_m_s: float | None = None, descent_m_s: float | None = None,
        yaw_deg: float = math.nan,
    ) -> None:
        """Fly the straight line to target_m; collision prevention may stop it short."""
        self.apply_params()
        dyn, k = self.fleet.dyn, self.k
        if speed_m_s is not None:
            dyn.speed_xy_m_s[k] = min(speed_m_s, self.params["MPC_XY_VEL_MAX"])
        if climb_m_s is not None:
            dyn.climb_m_s[k] = climb_m_s
        if descent_m_s is not None:
            dyn.descent_m_s[k] = descent_m_s
        if self.in_air:  # any new goal ends a take-off climb or a final descent
            self.landed_state = LandedState.IN_AIR
        blockage = self.fleet.world.first_blockage(self.position_m, target_m)
        self._blockage = blockage
        self._on_arrive = then
        if blockage is not None:
            self._set_goal(blockage.stop_m, dy.TRACK_SETTLE, yaw_deg=yaw_deg)
        else:
            self._set_goal(target_m, tracking, yaw_deg=yaw_deg)
            if tracking == dy.TRACK_NONE:
                self._goal_pending = True  # reported by touchdown instead
                self._refresh_busy()

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

    def _hold_at_current(self) -> None:
        self._on_arrive = None
        self._blockage = None
        self._set_goal(self.position_m, dy.TRACK_NONE)

    # --------------------------------------------------------- physics events
    def on_arrived(self) -> None:
        self._goal_pending = False
        blockage, self._blockage = self._blockage, None
        callback, self._on_arrive = self._on_arrive, None
        if blockage is not None:
            self._stopped_by(blockage.obstacle.id, blockage.obstacle.name)
        elif callback is not None:
            callback()
        self._refresh_busy()

    def on_obstacle_stop(self) -> None:
        self._blockage = None
        self._hold_at_current()
        self._stopped_by(None, "obstacle")

    def _stopped_by(self, obstacle_id: str | None, name: str) -> None:
        x, y, z = self.position_m
        self._event("obstacle_stop", obstacle=obstacle_id, position_m=[x, y, z])
        self._say(Severity.WARNING, f"Obstacle {name} ahead: holding")
        if self.mode is not FlightMode.OFFBOARD:
            self.mission.pause()
            self._set_mode(FlightMode.HOLD)
        self._goal_pending = False
        self._refresh_busy()

    def on_touchdown(self) -> None:
        dyn, k = self.fleet.dyn, self.k
        dyn.control[k] = dy.CONTROL_NONE
        dyn.tracking[k] = dy.TRACK_NONE
        dyn.velocity_m_s[k] = 0.0
        dyn.position_m[k, 2] = 0.0
        self.fleet.airborne[k] = False
        self.landed_state = LandedState.ON_GROUND
        self._goal_pending = False
        self._on_arrive = None
        x, y, _ = self.position_m
        self._event("landed", position_m=[x, y, 0.0])
        self.listener.on_state_changed()
        self._say(Severity.INFO, "Landing detected")
        self.mission.on_landed()
        delay = self.params["COM_DISARM_LAND"]
        if delay >= 0.0:
            self._set_timer(delay, self._auto_disarm, busy=True)
        self._refresh_busy()

    def on_yaw_reached(self) -> None:
        self._refresh_busy()
        self.mission.on_yaw_reached()

    def on_timer(self) -> None:
        action, self._timer_action = self._timer_action, None
        self._timer_busy = False
        if action is not None:
            action()
        self._refresh_busy()

    def on_battery_level(self, level: int) -> None:
        pct = self.battery_pct
        if level == BATTERY_LOW:
            self._say(Severity.WARNING, f"Low battery: {pct:.0f}% remaining")
        elif level == BATTERY_CRITICAL and self.in_air and self.mode not in (
            FlightMode.RTL, FlightMode.LAND
        ):
            self._event("failsafe", reason="battery_critical", battery_pct=pct)
            self._say(Severity.CRITICAL, f"Critical battery {pct:.0f}%: returning home")
            self._start_rtl()
        elif level == BATTERY_EMERGENCY and self.in_air and self.mode is not FlightMode.LAND:
            self._event("failsafe", reason="battery_emergency", battery_pct=pct)
            self._say(Severity.CRITICAL, f"Emergency battery {pct:.0f}%: landing")
            self._start_land(None)
        self._update_charging()

    # --------------------------------------------------------------- commands
    def arm(self) -> None:
        if self.armed:
            return
        self.failures.check_arming()
        if self.fleet.bat.level[self.k] >= BATTERY_CRITICAL:
            raise CommandRefused(f"Arming denied: battery {self.battery_pct:.0f}% too low")
        self.fleet.armed[self.k] = True
        self._event("arm")
        self.listener.on_state_changed()
        self._update_charging()
        delay = self.params["COM_DISARM_PRFLT"]
        if delay > 0.0:
            self._set_timer(delay, self._preflight_disarm, busy=False)
        if self.mode is FlightMode.MISSION:
            self.mission.start_or_resume()
        elif self.mode is FlightMode.OFFBOARD:
            self.offboard.apply()

    def disarm(self, *, force: bool = False) -> None:
        if not self.armed:
            return
        if self.in_air and not force:
            raise CommandRefused("Disarming denied: vehicle is in the air")
        if self.in_air:  # forced: motors stop and it falls; treated as an immediate landing
            self._event("kill", position_m=list(self.position_m))
            self.on_touchdown()
        self._cancel_timer()
        self.fleet.armed[self.k] = False
        self.fleet.dyn.control[self.k] = dy.CONTROL_NONE
        self._event("disarm")
        self.listener.on_state_changed()
        self._say(Severity.INFO, "Disarmed")
        self._update_charging()
        self._refresh_busy()

    def _auto_disarm(self) -> None:
        if self.armed and not self.in_air:
            self.disarm()
        if self.mode in (FlightMode.LAND, FlightMode.RTL, FlightMode.TAKEOFF):
            self._set_mode(FlightMode.HOLD)

    def _preflight_disarm(self) -> None:
        if self.armed and not self.in_air:
            self._say(Severity.INFO, "Disarmed: no takeoff after arming")
            self.disarm()

    def takeoff(self, altitude_m: float | None = None) -> None:
        if not self.armed:
            raise CommandRefused("Takeoff refused: arm first")
        if self.in_air:
            raise CommandRefused("Takeoff refused: already in the air")
        if altitude_m is None or math.isnan(altitude_m):
            altitude_m = self.params["MIS_TAKEOFF_ALT"]
        x, y, z = self.position_m
        target = (x, y, self.home_m[2] + altitude_m)
        check_altitude(self.params, self.home_m, target[2], "Takeoff")
        if target[2] <= z + 0.5:
            raise CommandRefused(f"Takeoff refused: altitude {altitude_m:.1f} m too low")
        self._set_mode(FlightMode.TAKEOFF)
        self.begin_climb(target, self._takeoff_complete)

    def begin_climb(self, target_m: Vec3, then: Callable[[], None]) -> None:
        """Leave the ground and climb vertically to target_m."""
        self._cancel_timer()
        self.fleet.airborne[self.k] = True
        self._update_charging()
        self._event("takeoff", altitude_m=target_m[2])
        self.fly_to(target_m, then=then, climb_m_s=self.params["MPC_TKO_SPEED"])
        self.landed_state = LandedState.TAKEOFF

    def _takeoff_complete(self) -> None:
        self.landed_state = LandedState.IN_AIR
        self._event("takeoff_complete", position_m=list(self.position_m))
        self.listener.on_state_changed()
        self._set_mode(FlightMode.HOLD)

    def land(self, at_m: tuple[float, float] | None = None) -> None:
        self._require_air("Land")
        if at_m is not None:
            check_distance_from_home(self.params, self.home_m, at_m[0], at_m[1], "Land")
        self._start_land(at_m)

    def _start_land(self, at_m: tuple[float, float] | None) -> None:
        self.mission.pause()
        self._set_mode(FlightMode.LAND)
        self.descend_and_land(at_m)

    def descend_and_land(self, at_m: tuple[float, float] | None) -> None:
        x, y, z = self.position_m
        if at_m is not None and math.hypot(at_m[0] - x, at_m[1] - y) > 0.5:
            self.fly_to((at_m[0], at_m[1], z), then=lambda: self.descend_and_land(None))
            return
        slow_alt = self.params["MPC_LAND_ALT2"]
        if z > slow_alt + 0.5:
            self.fly_to((x, y, slow_alt), then=self._final_descent, tracking=dy.TRACK_PASS)
        else:
            self._final_descent()

    def _final_descent(self) -> None:
        x, y, _ = self.position_m
        self.fly_to((x, y, GROUND_GOAL_Z_M), tracking=dy.TRACK_NONE,
                    descent_m_s=self.params["MPC_LAND_SPEED"])
        self.landed_state = LandedState.LANDING

    def return_to_launch(self) -> None:
        self._require_air("Return to launch")
        self._start_rtl()

    def _start_rtl(self) -> None:
        self.mission.pause()
        self._set_mode(FlightMode.RTL)
        x, y, z = self.position_m
        hx, hy, hz = self.home_m
        if math.hypot(hx - x, hy - y) < self.params["NAV_ACC_RAD"]:
            self.descend_and_land((hx, hy))
            return
        return_alt = max(z, hz + self.params["RTL_RETURN_ALT"])
        if return_alt > z + 0.5:
            self.fly_to((x, y, return_alt), then=self._rtl_return)
        else:
            self._rtl_return()

    def _rtl_return(self) -> None:
        hx, hy, _ = self.home_m
        self.fly_to((hx, hy, self.position_m[2]), then=lambda: self.descend_and_land((hx, hy)))

    def hold(self) -> None:
        """Switch to HOLD: always accepted (clients send it before arming)."""
        self.mission.pause()
        self._set_mode(FlightMode.HOLD)
        if self.in_air:
            self.brake_and_hold()

    def reposition(self, target_m: Vec3, *, speed_m_s: float | None = None,
                   yaw_deg: float = math.nan) -> None:
        """Go to a point and hold there (PX4 DO_REPOSITION)."""
        self._require_air("Reposition")
        self.check_target(target_m, "Reposition")
        if speed_m_s is not None:
            check_speed(self.params, SpeedKind.GROUND, speed_m_s, "Reposition")
        self.mission.pause()
        self._set_mode(FlightMode.HOLD)
        self.fly_to(target_m, speed_m_s=speed_m_s, yaw_deg=yaw_deg)
        if math.isfinite(yaw_deg):  # a commanded heading is part of the goal
            self.fleet.dyn.yaw_tracking[self.k] = True
            self._refresh_busy()

    def change_speed(self, kind: float, speed_m_s: float) -> None:
        """MAV_CMD_DO_CHANGE_SPEED: speed -1 or -2 restores the configured value."""
        if kind not in tuple(SpeedKind):
            raise CommandRefused(f"Speed: unknown speed type {kind:g}")
        speed_kind = SpeedKind(int(kind))
        dyn, k, p = self.fleet.dyn, self.k, self.params
        horizontal = speed_kind in (SpeedKind.AIRSPEED, SpeedKind.GROUND)
        if speed_m_s == -1.0 or speed_m_s == -2.0:
            if horizontal:
                self.speed_override_m_s = None
                dyn.speed_xy_m_s[k] = min(p["MPC_XY_CRUISE"], p["MPC_XY_VEL_MAX"])
            elif speed_kind is SpeedKind.CLIMB:
                dyn.climb_m_s[k] = p["MPC_Z_VEL_MAX_UP"]
            else:
                dyn.descent_m_s[k] = p["MPC_Z_VEL_MAX_DN"]
            return
        check_speed(p, speed_kind, speed_m_s, "Speed")
        if horizontal:
            self.speed_override_m_s = speed_m_s
            dyn.speed_xy_m_s[k] = speed_m_s
        elif speed_kind is SpeedKind.CLIMB:
            dyn.climb_m_s[k] = speed_m_s
        else:
            dyn.descent_m_s[k] = speed_m_s

    def set_yaw(self, heading_deg: float, *, rate_deg_s: float = 0.0,
                relative: bool = False, direction: int = 1) -> None:
        self._require_air("Yaw")
        if not math.isfinite(heading_deg) or not math.isfinite(rate_deg_s):
            raise CommandRefused("Yaw refused: angle and rate must be numbers")
        if rate_deg_s > 0.0:
            check_yaw_rate(self.params, rate_deg_s, "Yaw")
        dyn, k = self.fleet.dyn, self.k
        if relative:
            heading_deg = float(dyn.yaw_deg[k]) + (heading_deg if direction >= 0 else -heading_deg)
        target = wrap_heading_deg(heading_deg)
        max_rate = self.params["MPC_YAWRAUTO_MAX"]
        dyn.yaw_rate_deg_s[k] = min(rate_deg_s, max_rate) if rate_deg_s > 0 else max_rate
        dyn.goal_yaw_deg[k] = target
        if dyn.control[k] == dy.CONTROL_NONE:
            self._hold_at_current()
        dyn.yaw_tracking[k] = True
        self._refresh_busy()

    def set_home(self, home_m: Vec3) -> None:
        """Move home; refused beyond SIM_HOME_MAXDIST or the geofence (see limits)."""
        self.home_m = check_home(self.params, home_m, self.position_m)
        self._event("home", position_m=list(self.home_m))
        self.listener.on_home_changed()

    def set_mode(self, mode: FlightMode, *, wall_now_s: float = 0.0) -> None:
        if mode is FlightMode.HOLD:
            self.hold()
        elif mode is FlightMode.MISSION:
            self.mission.enter_mission_mode()
        elif mode is FlightMode.RTL:
            self.return_to_launch()
        elif mode is FlightMode.LAND:
            if self.in_air:
                self._start_land(None)
            else:
                self._set_mode(FlightMode.LAND)
        elif mode is FlightMode.TAKEOFF:
            self.takeoff(None)
        elif mode is FlightMode.OFFBOARD:
            self.offboard.enter(wall_now_s)
        else:
            raise CommandRefused(f"Mode {mode.label} refused: no manual control input")

    # ------------------------------------------------------------------ camera
    def take_photo(self) -> ImageCapture:
        """Trigger the camera: record what it captured and announce the image."""
        capture = capture_image(self)
        self.listener.on_image_captured(capture)
        return capture

    # ---------------------------------------------------------------- charging
    def on_charged(self) -> None:
        self.fleet.bat.charge_rate_pct_s[self.k] = 0.0
        self._event("charged", battery_pct=self.battery_pct)
        self._say(Severity.INFO, "Battery charged")
        self._refresh_busy()

    def _update_charging(self) -> None:
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
            self._event("charging", battery_pct=self.battery_pct)
        self._refresh_busy()
