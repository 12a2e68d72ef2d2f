"""One vehicle's PX4-like flight logic: arming, modes, sequences and failsafes.

The autopilot never moves its vehicle itself: it sets goals (a position to fly to, a
velocity, a yaw) through emulator.flight.vehicle.Vehicle and the vectorised dynamics fly
them. It reacts to what the physics reports (arrived, touched down, stopped by an obstacle,
battery level, timers): an arrival advances the sequence the goal belongs to
(emulator.flight.sequences, the mission runner). Commands that cannot be carried out raise
:class:`CommandRefused` before anything changes.
"""

from __future__ import annotations

import math

from emulator.flight import dynamics as dy
from emulator.flight import sequences
from emulator.flight.autopilot_mission import MissionRunner
from emulator.flight.battery import BATTERY_CRITICAL, BATTERY_EMERGENCY, BATTERY_LOW
from emulator.flight.camera import ImageCapture, capture_image
from emulator.flight.failures import VehicleFailures
from emulator.flight.fleet_view import FleetView
from emulator.flight.follow_target import FollowTarget
from emulator.flight.geofence_plans import GeofencePlans
from emulator.flight.limits import SpeedKind, check_home, check_speed, check_yaw_rate
from emulator.flight.listener import AutopilotListener
from emulator.flight.manual_control import MANUAL_MODES, ManualControl
from emulator.flight.modes import FlightMode, LandedState
from emulator.flight.offboard import OffboardControl
from emulator.flight.orbit import OrbitControl
from emulator.flight.refusal import CommandRefused, Severity
from emulator.flight.vehicle import Vehicle
from emulator.flight.vehicle_state import MISSION_PHASES, Phase, TimerAction
from emulator.geo import wrap_heading_deg
from emulator.scenario import VehicleSpec
from emulator.truth_events import TruthEventKind
from mavlink_vocabulary import BatteryFailsafe, BatteryLevel, LowBattery, ObstacleHold

__all__ = ["Autopilot", "AutopilotListener", "CommandRefused", "ImageCapture", "Severity"]

Vec3 = tuple[float, float, float]


class Autopilot(Vehicle):
    """Flight logic of vehicle `k` of a fleet."""

    def __init__(self, k: int, spec: VehicleSpec, fleet: FleetView) -> None:
        super().__init__(k, spec, fleet)
        self.mission = MissionRunner(self)
        self.offboard = OffboardControl(self)
        self.orbit = OrbitControl(self)
        self.manual = ManualControl(self)
        self.follow = FollowTarget(self)
        self.geofence = GeofencePlans(self)
        self.failures = VehicleFailures(self)

    def pause_mission(self) -> None:
        self.mission.pause()

    def check_target(self, target_m: Vec3, what: str) -> None:
        """Refuse a destination outside the geofence (parameters and fence plan)."""
        super().check_target(target_m, what)
        self.geofence.check_target(target_m, what)

    def rtl_destination_m(self) -> Vec3:
        return self.geofence.rtl_destination_m()

    # --------------------------------------------------------- physics events
    def on_arrived(self) -> None:
        """The goal is reached: the sequence it belongs to takes its next step."""
        st = self.state
        st.goal_pending = False
        blockage, st.blockage = st.blockage, None
        phase, st.phase = st.phase, Phase.IDLE
        if blockage is not None:
            self._stopped_by(blockage.obstacle.id, blockage.obstacle.name)
        elif phase in MISSION_PHASES:
            self.mission.on_arrived(phase, st.item_seq, st.item_wait_s)
        else:
            sequences.advance(self, phase, st.land_at_m)
        self.refresh_busy()

    def on_obstacle_stop(self) -> None:
        self.state.blockage = None
        self.hold_position()
        self._stopped_by(None, "obstacle")

    def _stopped_by(self, obstacle_id: str | None, name: str) -> None:
        x, y, z = self.position_m
        self.event(TruthEventKind.OBSTACLE_STOP, obstacle=obstacle_id, position_m=[x, y, z])
        self.announce(ObstacleHold(name))
        if self.state.mode is not FlightMode.OFFBOARD:
            self.mission.pause()
            self.switch_mode(FlightMode.HOLD)
        self.state.goal_pending = False
        self.refresh_busy()

    def on_touchdown(self) -> None:
        dyn, k = self.fleet.dyn, self.k
        dyn.control[k] = dy.CONTROL_NONE
        dyn.tracking[k] = dy.TRACK_NONE
        dyn.velocity_m_s[k] = 0.0
        dyn.position_m[k, 2] = 0.0
        self.fleet.airborne[k] = False
        st = self.state
        st.landed_state = LandedState.ON_GROUND
        st.goal_pending = False
        st.phase = Phase.IDLE
        x, y, _ = self.position_m
        self.event(TruthEventKind.LANDED, position_m=[x, y, 0.0])
        self.listener.on_state_changed()
        self.say(Severity.INFO, "Landing detected")
        self.mission.on_landed()
        delay = self.params["COM_DISARM_LAND"]
        if delay >= 0.0:
            self.set_timer(delay, TimerAction.AUTO_DISARM, busy=True)
        self.refresh_busy()

    def on_velocity_step(self, dt_s: float) -> None:
        """After every physics step flown by velocity: the mode sets the next one."""
        mode = self.state.mode
        if mode is FlightMode.ORBIT:
            self.orbit.on_step()
        elif mode in MANUAL_MODES:
            self.manual.on_step(dt_s)
            self.offboard.check_fence()
        elif mode is FlightMode.FOLLOW_TARGET:
            self.follow.on_step(dt_s)
            self.offboard.check_fence()
        else:
            self.offboard.on_step(dt_s)

    def on_yaw_reached(self) -> None:
        self.refresh_busy()
        self.mission.on_yaw_reached()

    def on_timer(self) -> None:
        st = self.state
        action, seq = st.timer, st.timer_seq
        st.timer, st.timer_busy = TimerAction.NONE, False
        if action is TimerAction.AUTO_DISARM:
            self._auto_disarm()
        elif action is TimerAction.PREFLIGHT_DISARM:
            self._preflight_disarm()
        elif action is not TimerAction.NONE:
            self.mission.on_timer(action, seq)
        self.refresh_busy()

    def on_battery_level(self, level: int) -> None:
        pct = self.battery_pct
        if level == BATTERY_LOW:
            self.announce(LowBattery(pct))
        elif level == BATTERY_CRITICAL and self.in_air and self.mode not in (
            FlightMode.RTL, FlightMode.LAND
        ):
            self.event(TruthEventKind.FAILSAFE, reason="battery_critical", battery_pct=pct)
            self.announce(BatteryFailsafe(BatteryLevel.CRITICAL, pct))
            self.start_rtl()
        elif level == BATTERY_EMERGENCY and self.in_air and self.mode is not FlightMode.LAND:
            self.event(TruthEventKind.FAILSAFE, reason="battery_emergency", battery_pct=pct)
            self.announce(BatteryFailsafe(BatteryLevel.EMERGENCY, pct))
            self.start_land(None)
        self.update_charging()

    # --------------------------------------------------------------- commands
    def arm(self) -> None:
        if self.armed:
            return
        self.failures.check_arming()
        self.geofence.check_arming()
        if self.fleet.bat.level[self.k] >= BATTERY_CRITICAL:
            raise CommandRefused(f"Arming denied: battery {self.battery_pct:.0f}% too low")
        self.fleet.armed[self.k] = True
        self.event(TruthEventKind.ARM)
        self.listener.on_state_changed()
        self.update_charging()
        delay = self.params["COM_DISARM_PRFLT"]
        if delay > 0.0:
            self.set_timer(delay, TimerAction.PREFLIGHT_DISARM, busy=False)
        if self.mode is FlightMode.MISSION:
            self.mission.start_or_resume()
        elif self.mode is FlightMode.OFFBOARD:
            self.offboard.apply()
        elif self.mode in MANUAL_MODES:
            self.manual.apply()

    def disarm(self, *, force: bool = False) -> None:
        if not self.armed:
            return
        if self.in_air and not force:
            raise CommandRefused("Disarming denied: vehicle is in the air")
        if self.in_air:  # forced: motors stop and it falls; treated as an immediate landing
            self.event(TruthEventKind.KILL, position_m=list(self.position_m))
            self.on_touchdown()
        self.cancel_timer()
        self.fleet.armed[self.k] = False
        self.fleet.dyn.control[self.k] = dy.CONTROL_NONE
        self.event(TruthEventKind.DISARM)
        self.listener.on_state_changed()
        self.say(Severity.INFO, "Disarmed")
        self.update_charging()
        self.refresh_busy()

    def _auto_disarm(self) -> None:
        if self.armed and not self.in_air:
            self.disarm()
        if self.mode in (FlightMode.LAND, FlightMode.RTL, FlightMode.TAKEOFF):
            self.switch_mode(FlightMode.HOLD)

    def _preflight_disarm(self) -> None:
        if self.armed and not self.in_air:
            self.say(Severity.INFO, "Disarmed: no takeoff after arming")
            self.disarm()

    # ------------------------------------------- sequences (emulator.flight.sequences)
    def takeoff(self, altitude_m: float | None = None) -> None:
        sequences.takeoff(self, altitude_m)

    def begin_climb(self, target_m: Vec3, phase: Phase) -> None:
        """Leave the ground and climb vertically to target_m as step `phase`."""
        sequences.begin_climb(self, target_m, phase)

    def land(self, at_m: tuple[float, float] | None = None) -> None:
        sequences.land(self, at_m)

    def start_land(self, at_m: tuple[float, float] | None) -> None:
        """LAND mode without the command's checks (a failsafe)."""
        sequences.start_land(self, at_m)

    def descend_and_land(self, at_m: tuple[float, float] | None) -> None:
        sequences.descend_and_land(self, at_m)

    def return_to_launch(self) -> None:
        sequences.return_to_launch(self)

    def start_rtl(self) -> None:
        """RTL mode without the command's checks (a failsafe or a mission item)."""
        sequences.start_rtl(self)

    def hold(self) -> None:
        """Switch to HOLD: always accepted (clients send it before arming)."""
        self.mission.pause()
        self.switch_mode(FlightMode.HOLD)
        if self.in_air:
            self.brake_and_hold()

    def reposition(self, target_m: Vec3, *, speed_m_s: float | None = None,
                   yaw_deg: float = math.nan) -> None:
        """Go to a point and hold there (PX4 DO_REPOSITION)."""
        sequences.require_air(self, "Reposition")
        self.check_target(target_m, "Reposition")
        if speed_m_s is not None:
            check_speed(self.params, SpeedKind.GROUND, speed_m_s, "Reposition")
        self.mission.pause()
        self.switch_mode(FlightMode.HOLD)
        self.fly_to(target_m, speed_m_s=speed_m_s, yaw_deg=yaw_deg)
        if math.isfinite(yaw_deg):  # a commanded heading is part of the goal
            self.fleet.dyn.yaw_tracking[self.k] = True
            self.refresh_busy()

    def change_speed(self, kind: float, speed_m_s: float) -> None:
        """MAV_CMD_DO_CHANGE_SPEED: speed -1 or -2 restores the configured value."""
        if kind not in tuple(SpeedKind):
            raise CommandRefused(f"Speed: unknown speed type {kind:g}")
        speed_kind = SpeedKind(int(kind))
        dyn, k, p = self.fleet.dyn, self.k, self.params
        horizontal = speed_kind in (SpeedKind.AIRSPEED, SpeedKind.GROUND)
        if speed_m_s == -1.0 or speed_m_s == -2.0:
            if horizontal:
                self.state.speed_override_m_s = None
                dyn.speed_xy_m_s[k] = min(p["MPC_XY_CRUISE"], p["MPC_XY_VEL_MAX"])
            elif speed_kind is SpeedKind.CLIMB:
                dyn.climb_m_s[k] = p["MPC_Z_VEL_MAX_UP"]
            else:
                dyn.descent_m_s[k] = p["MPC_Z_VEL_MAX_DN"]
            return
        check_speed(p, speed_kind, speed_m_s, "Speed")
        if horizontal:
            self.state.speed_override_m_s = speed_m_s
            dyn.speed_xy_m_s[k] = speed_m_s
        elif speed_kind is SpeedKind.CLIMB:
            dyn.climb_m_s[k] = speed_m_s
        else:
            dyn.descent_m_s[k] = speed_m_s

    def set_yaw(self, heading_deg: float, *, rate_deg_s: float = 0.0,
                relative: bool = False, direction: int = 1) -> None:
        sequences.require_air(self, "Yaw")
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
            self.hold_position()
        dyn.yaw_tracking[k] = True
        self.refresh_busy()

    def set_home(self, home_m: Vec3) -> None:
        """Move home; refused beyond SIM_HOME_MAXDIST or the geofence (see limits)."""
        self.state.home_m = check_home(self.params, home_m, self.position_m)
        self.event(TruthEventKind.HOME, position_m=list(self.state.home_m))
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
                self.start_land(None)
            else:
                self.switch_mode(FlightMode.LAND)
        elif mode is FlightMode.TAKEOFF:
            self.takeoff(None)
        elif mode is FlightMode.OFFBOARD:
            self.offboard.enter(wall_now_s)
        elif mode in MANUAL_MODES:
            self.manual.enter(mode, wall_now_s)
        elif mode is FlightMode.FOLLOW_TARGET:
            self.follow.enter()
        else:
            raise CommandRefused(f"Mode {mode.label} refused: only posctl/altctl flown")

    # ------------------------------------------------------------------ camera
    def take_photo(self) -> ImageCapture:
        """Trigger the camera: record what it captured and announce the image."""
        self.state.photo_count += 1
        capture = capture_image(self, self.state.photo_count)
        self.listener.on_image_captured(capture)
        return capture

    # ---------------------------------------------------------------- charging
    def on_charged(self) -> None:
        self.fleet.bat.charge_rate_pct_s[self.k] = 0.0
        self.event(TruthEventKind.CHARGED, battery_pct=self.battery_pct)
        self.say(Severity.INFO, "Battery charged")
        self.refresh_busy()
