"""Mission execution for one autopilot: item by item, with progress and pauses.

A positional item is a goal of one of the mission phases (emulator.flight.vehicle_state.Phase);
its arrival comes back through `on_arrived`, a hold or loiter time through `on_timer`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from emulator.flight import dynamics as dy
from emulator.flight.mission import PAYLOAD_COMMANDS, Cmd, MissionItem
from emulator.flight.modes import FlightMode
from emulator.flight.refusal import CommandRefused, Severity
from emulator.flight.vehicle_control import VehicleControl
from emulator.flight.vehicle_state import Phase, TimerAction
from emulator.truth_events import TruthEventKind

__all__ = ["MissionRunner", "MissionState"]


class MissionState:
    """MISSION_STATE values reported in MISSION_CURRENT."""

    NO_MISSION = 1
    NOT_STARTED = 2
    ACTIVE = 3
    PAUSED = 4
    COMPLETE = 5


class MissionRunner:
    """The stored mission of one vehicle and where it stands in it."""

    def __init__(self, autopilot: VehicleControl) -> None:
        self.ap = autopilot
        self.items: tuple[MissionItem, ...] = ()
        self.current = 0
        self.state = MissionState.NO_MISSION
        self.active = False
        self._awaiting_yaw = False

    @property
    def total(self) -> int:
        return len(self.items)

    def replace(self, items: Sequence[MissionItem]) -> None:
        """Store a newly uploaded mission (an executing one stops and holds)."""
        was_running = self.active
        self.pause()
        self.items = tuple(items)
        self.current = 0
        self.state = MissionState.NOT_STARTED if self.items else MissionState.NO_MISSION
        if was_running and self.ap.in_air:
            self.ap.brake_and_hold()
        self.ap.listener.on_mission_current()

    def clear(self) -> None:
        self.replace(())

    def set_current(self, seq: int) -> None:
        if not 0 <= seq < self.total:
            raise CommandRefused(f"Mission item {seq} does not exist (mission has {self.total})")
        self.current = seq
        if self.state == MissionState.COMPLETE:
            self.state = MissionState.PAUSED
        if self.active:
            self._execute(seq)
        else:
            self.ap.listener.on_mission_current()

    def enter_mission_mode(self, first: int | None = None) -> None:
        if not self.items:
            raise CommandRefused("Mission refused: no mission uploaded")
        if first is not None and not 0 <= first < self.total:
            raise CommandRefused(f"Mission refused: no item {first}")
        if first is not None:
            self.current = first
        self.ap.switch_mode(FlightMode.MISSION)
        if self.ap.armed:
            self.start_or_resume()

    def start_or_resume(self) -> None:
        ap = self.ap
        if not self.items:
            return
        if self.state == MissionState.COMPLETE:
            self.current = 0
        self.active = True
        self.state = MissionState.ACTIVE
        ap.event(TruthEventKind.MISSION_START, item=self.current, total=self.total)
        if ap.in_air:
            self._execute(self.current)
            return
        item = self.items[self.current]
        x, y, _ = ap.position_m
        if item.command == Cmd.NAV_TAKEOFF:
            _, _, z = self._target(item)
            ap.state.item_seq = self.current
            ap.begin_climb((x, y, z), Phase.MISSION_TAKEOFF)
        else:
            alt = ap.state.home_m[2] + ap.params["MIS_TAKEOFF_ALT"]
            ap.begin_climb((x, y, alt), Phase.MISSION_CLIMB)
        ap.listener.on_mission_current()

    def pause(self) -> None:
        if self.active:
            self.active = False
            self.state = MissionState.PAUSED
            self._awaiting_yaw = False
            self._cancel_wait()
            self.ap.listener.on_mission_current()

    def _wait(self, delay_s: float, then: TimerAction, seq: int) -> None:
        """`then` for item `seq` after delay_s of simulated time (a hold, loiter or delay)."""
        self.ap.set_timer(delay_s, then, busy=True, seq=seq)

    def _cancel_wait(self) -> None:
        """A paused mission's pending hold must not fire into a later flight or mission."""
        if self.ap.state.timer in (TimerAction.MISSION_NEXT, TimerAction.MISSION_REACHED_NEXT):
            self.ap.cancel_timer()
            self.ap.refresh_busy()

    def on_timer(self, action: TimerAction, seq: int) -> None:
        """The wait of item `seq` ended."""
        if action is TimerAction.MISSION_NEXT:
            self._execute(seq + 1)
        elif action is TimerAction.MISSION_REACHED_NEXT:
            self._reached_then_next(seq)

    def on_arrived(self, phase: Phase, seq: int, wait_s: float) -> None:
        """The goal of item `seq` (of mission phase `phase`) is reached."""
        if phase is Phase.MISSION_CLIMB:
            self._execute(self.current)
        elif phase is Phase.MISSION_TAKEOFF:
            self._reached_then_next(seq)
        elif phase is Phase.MISSION_WAYPOINT:
            if not self.active:
                return
            self._reached(seq)
            if wait_s > 0:
                self._wait(wait_s, TimerAction.MISSION_NEXT, seq)
            else:
                self._execute(seq + 1)
        elif phase is Phase.MISSION_LOITER:
            if self.active:
                self._wait(wait_s, TimerAction.MISSION_REACHED_NEXT, seq)
        elif phase is Phase.MISSION_LOITER_UNLIMITED:
            self._reached(seq)

    def _fly_to_item(self, target_m: tuple[float, float, float], phase: Phase, seq: int,
                     wait_s: float = 0.0, *, tracking: int = dy.TRACK_SETTLE,
                     yaw_deg: float = math.nan) -> None:
        """Fly to item `seq` as `phase`; `wait_s` is the hold or loiter time there."""
        self.ap.state.item_seq, self.ap.state.item_wait_s = seq, wait_s
        self.ap.fly_to(target_m, phase=phase, tracking=tracking, yaw_deg=yaw_deg)

    # ---------------------------------------------------------------- progress
    def _execute(self, seq: int) -> None:
        if not self.active:
            return
        if seq >= self.total:
            self._complete()
            return
        self.current = seq
        self.ap.listener.on_mission_current()
        item = self.items[seq]
        handler = _HANDLERS[item.command]
        handler(self, item)

    def _reached(self, seq: int) -> None:
        self.ap.event(TruthEventKind.MISSION_ITEM_REACHED, item=seq)
        self.ap.listener.on_mission_item_reached(seq)

    def _reached_then_next(self, seq: int) -> None:
        if not self.active:
            return
        self._reached(seq)
        self._execute(seq + 1)

    def _complete(self) -> None:
        self.active = False
        self.state = MissionState.COMPLETE
        self.current = max(0, self.total - 1)
        self.ap.event(TruthEventKind.MISSION_COMPLETE)
        self.ap.say(Severity.INFO, "Mission finished")
        self.ap.listener.on_mission_current()

    def _is_last_nav(self, seq: int) -> bool:
        return not any(it.is_nav for it in self.items[seq + 1:])

    def _target(self, item: MissionItem) -> tuple[float, float, float]:
        ap = self.ap
        return item.local_target_m(ap.fleet.world.origin, ap.state.home_m, ap.position_m)

    # ------------------------------------------------------------ per command
    def _waypoint(self, item: MissionItem) -> None:
        seq, hold_s = item.seq, item.param1 if math.isfinite(item.param1) else 0.0
        last = self._is_last_nav(seq)
        tracking = dy.TRACK_SETTLE if last or hold_s > 0 else dy.TRACK_PASS
        yaw = item.param4 if math.isfinite(item.param4) else math.nan
        self._fly_to_item(self._target(item), Phase.MISSION_WAYPOINT, seq, hold_s,
                          tracking=tracking, yaw_deg=yaw)

    def _takeoff(self, item: MissionItem) -> None:
        x, y, _ = self.ap.position_m
        _, _, z = self._target(item)
        self._fly_to_item((x, y, max(z, self.ap.position_m[2])), Phase.MISSION_TAKEOFF,
                          item.seq)

    def _loiter_time(self, item: MissionItem) -> None:
        self._fly_to_item(self._target(item), Phase.MISSION_LOITER, item.seq,
                          max(0.0, item.param1))

    def _loiter_unlimited(self, item: MissionItem) -> None:
        self._fly_to_item(self._target(item), Phase.MISSION_LOITER_UNLIMITED, item.seq)

    def _land(self, item: MissionItem) -> None:
        x, y, _ = self._target(item)
        self.ap.descend_and_land((x, y))

    def on_landed(self) -> None:
        if self.active and self.items[self.current].command == Cmd.NAV_LAND:
            self._reached(self.current)
            self._complete()

    def _rtl(self, item: MissionItem) -> None:
        self._reached(item.seq)
        self._complete()
        self.ap.start_rtl()

    def _delay(self, item: MissionItem) -> None:
        self._wait(max(0.0, item.param1), TimerAction.MISSION_NEXT, item.seq)

    def _yaw(self, item: MissionItem) -> None:
        self._awaiting_yaw = True
        rate = item.param2 if math.isfinite(item.param2) and item.param2 > 0 else 0.0
        try:
            self.ap.set_yaw(item.param1, rate_deg_s=rate, relative=item.param4 == 1,
                            direction=-1 if item.param3 < 0 else 1)
        except CommandRefused as refusal:
            self._awaiting_yaw = False
            self.ap.say(Severity.WARNING, str(refusal))
            self._execute(item.seq + 1)

    def on_yaw_reached(self) -> None:
        if self._awaiting_yaw and self.active:
            self._awaiting_yaw = False
            self._execute(self.current + 1)

    def _change_speed(self, item: MissionItem) -> None:
        try:
            self.ap.change_speed(item.param1 if math.isfinite(item.param1) else 1.0,
                                 item.param2)
        except CommandRefused as refusal:
            self.ap.say(Severity.WARNING, str(refusal))
        self._execute(item.seq + 1)

    def _photo(self, item: MissionItem) -> None:
        self.ap.take_photo()
        self._execute(item.seq + 1)

    def _pass_over(self, item: MissionItem) -> None:
        """A gimbal or camera item (PAYLOAD_COMMANDS): the payload acts on it, if it can,
        and the mission goes on."""
        self.ap.listener.on_payload_item(item)
        self._execute(item.seq + 1)


_HANDLERS: dict[int, Callable[[MissionRunner, MissionItem], None]] = {
    Cmd.NAV_WAYPOINT: MissionRunner._waypoint,
    Cmd.NAV_TAKEOFF: MissionRunner._takeoff,
    Cmd.NAV_LOITER_TIME: MissionRunner._loiter_time,
    Cmd.NAV_LOITER_UNLIM: MissionRunner._loiter_unlimited,
    Cmd.NAV_LAND: MissionRunner._land,
    Cmd.NAV_RETURN_TO_LAUNCH: MissionRunner._rtl,
    Cmd.NAV_DELAY: MissionRunner._delay,
    Cmd.CONDITION_YAW: MissionRunner._yaw,
    Cmd.DO_CHANGE_SPEED: MissionRunner._change_speed,
    Cmd.IMAGE_START_CAPTURE: MissionRunner._photo,
    **dict.fromkeys(PAYLOAD_COMMANDS, MissionRunner._pass_over),
}
