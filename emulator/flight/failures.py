"""Vehicle failures and the data-link-loss failsafe, as PX4 handles them.

Failures come from failure injection (MAV_CMD_INJECT_FAILURE with SYS_FAILURE_EN = 1) or from
a session's schedule; the data-link-loss failsafe from the link faults (see
emulator.swarm_faults). Each is a truth event. A failure lasts until the operator puts the
vehicle down between tasks (emulator.flight.operator).

- GPS off: the position estimate is lost; PX4 lands where it is (a multicopter without a
  position cannot hold or navigate) and refuses to arm until the GPS is back.
- Motor off: a quadrotor cannot fly on three motors: it comes down where it is and disarms
  on the ground; it refuses to arm for the rest of the task.
- Battery: the charge drops to the critical level at once; the battery failsafe (return home)
  follows.
- MAVLink signal off: the vehicle sends and hears nothing (the transport drops its frames);
  it keeps flying what it was doing until the data-link-loss failsafe acts.
"""

from __future__ import annotations

from emulator.flight import dynamics as dy
from emulator.flight.modes import FlightMode, LandedState
from emulator.flight.refusal import CommandRefused
from emulator.flight.vehicle_control import VehicleControl
from emulator.flight.vehicle_state import Phase
from emulator.truth_events import TruthEventKind
from mavlink_vocabulary import (
    BatteryFailure,
    DataLinkLost,
    FailsafeAction,
    GpsLost,
    MotorFailure,
    build_statustext,
)

__all__ = ["DLL_ACTIONS", "FAILURE_KINDS", "VehicleFailures"]

FAILURE_KINDS = ("gps", "motor", "battery", "mavlink")
DLL_ACTIONS = {1: "hold", 2: "return", 3: "land"}
BATTERY_DROP_BELOW_PCT = 0.5  # a battery failure leaves the charge this far below critical
MOTOR_DESCENT_M_S = 4.0  # the fastest descent a multicopter with a failed motor is given
GROUND_GOAL_Z_M = -1.0  # a descent aims below the ground until touchdown


class VehicleFailures:
    """The failures in force on one vehicle."""

    def __init__(self, ap: VehicleControl) -> None:
        self._ap = ap
        self.gps_off = False
        self.motor_off = False
        self.mavlink_off = False
        self.link_lost = False  # the data-link-loss failsafe has acted since the link was up
        # vehicles whose MAVLink is off: shared with the transport's link gate by the swarm
        self.silenced: set[int] = set()

    @property
    def any(self) -> bool:
        return self.gps_off or self.motor_off or self.mavlink_off

    def standing_report(self) -> tuple[int, str] | None:
        """The STATUSTEXT a vehicle out of the task keeps telling (the swarm sends it again with
        the vehicle's telemetry at a halt, so a report lost on the way still reaches the
        client); None when no such failure is in force."""
        report: MotorFailure | GpsLost
        in_air = self._ap.in_air  # the report the failure began with, while that still holds
        if self.motor_off:
            report = MotorFailure(falling=in_air)
        elif self.gps_off:
            report = GpsLost(landing=in_air)
        else:
            return None
        return report.severity, build_statustext(report)

    def check_arming(self) -> None:
        if self.motor_off:
            raise CommandRefused("Arming denied: motor failure")
        if self.gps_off:
            raise CommandRefused("Arming denied: no GPS fix")

    def clear(self) -> None:
        self.gps_off = self.motor_off = self.link_lost = False
        self._set_mavlink(False)

    def _set_mavlink(self, off: bool) -> None:
        self.mavlink_off = off
        if off:
            self.silenced.add(self._ap.k)
        else:
            self.silenced.discard(self._ap.k)

    # ------------------------------------------------------------- failures
    def fail(self, kind: str, source: str) -> None:
        """Inject a failure of `kind` (one of FAILURE_KINDS); `source` names who did."""
        ap = self._ap
        if kind not in FAILURE_KINDS:
            raise ValueError(f"unknown failure {kind!r} (known: {', '.join(FAILURE_KINDS)})")
        ap.event(TruthEventKind.FAILURE, unit=kind, source=source, position_m=list(ap.position_m))
        if kind == "gps":
            self.gps_off = True
            if ap.in_air:
                ap.event(TruthEventKind.FAILSAFE, reason="gps_lost")
                ap.announce(GpsLost(landing=True))
                ap.start_land(None)
        elif kind == "motor":
            self.motor_off = True
            if ap.in_air:
                ap.event(TruthEventKind.FAILSAFE, reason="motor_failure")
                ap.announce(MotorFailure(falling=True))
                ap.pause_mission()
                ap.switch_mode(FlightMode.LAND)
                x, y, _ = ap.position_m
                ap.fly_to((x, y, GROUND_GOAL_Z_M), phase=Phase.FALLING, tracking=dy.TRACK_NONE,
                          descent_m_s=MOTOR_DESCENT_M_S)
                ap.state.landed_state = LandedState.LANDING
            else:  # one report of the failure, as it stands (see standing_report)
                if ap.armed:
                    ap.disarm()
                ap.announce(MotorFailure(falling=False))
        elif kind == "battery":
            bat, k = ap.fleet.bat, ap.k
            bat.pct[k] = max(0.0, min(float(bat.pct[k]),
                                      float(bat.critical_pct[k]) - BATTERY_DROP_BELOW_PCT))
            before = int(bat.level[k])
            bat.step(0.0, ap.fleet.airborne, ap.fleet.armed, ap.fleet.dyn.airspeed_m_s(),
                     ap.fleet.dyn.velocity_m_s[:, 2])
            ap.announce(BatteryFailure(ap.battery_pct))
            if int(bat.level[k]) != before:
                ap.on_battery_level(int(bat.level[k]))
        else:
            self._set_mavlink(True)
        ap.listener.on_state_changed()

    def restore(self, kind: str, source: str) -> None:
        """A failure cleared by injection of 'ok' (GPS and MAVLink signal only)."""
        if kind == "gps" and self.gps_off:
            self.gps_off = False
            self._ap.event(TruthEventKind.FAILURE_CLEARED, unit=kind, source=source)
        elif kind == "mavlink" and self.mavlink_off:
            self._set_mavlink(False)
            self._ap.event(TruthEventKind.FAILURE_CLEARED, unit=kind, source=source)

    # --------------------------------------------------------- link failsafe
    def data_link_lost(self, timeout_s: float) -> None:
        """Nothing heard from any ground station for COM_DL_LOSS_T: NAV_DLL_ACT."""
        ap = self._ap
        if self.link_lost:
            return
        self.link_lost = True
        action = DLL_ACTIONS.get(int(ap.params["NAV_DLL_ACT"]))
        ap.event(TruthEventKind.LINK_LOST, timeout_s=timeout_s, action=action or "none")
        if action is None or not ap.in_air or self.motor_off:
            return
        ap.event(TruthEventKind.FAILSAFE, reason="data_link_lost", action=action)
        ap.announce(DataLinkLost(FailsafeAction(action)))
        if action == "hold":
            ap.hold()
        elif action == "return" and ap.state.mode is not FlightMode.RTL:
            ap.start_rtl()
        elif action == "land" and ap.state.mode is not FlightMode.LAND:
            ap.start_land(None)

    def data_link_regained(self) -> None:
        if self.link_lost:
            self.link_lost = False
            self._ap.event(TruthEventKind.LINK_REGAINED)
