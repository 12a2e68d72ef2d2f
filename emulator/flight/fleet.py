"""The fleet: every vehicle's arrays, its autopilots and the fixed-step physics tick."""

from __future__ import annotations

import math

import numpy as np

from emulator.flight.arrays import any_true as _any
from emulator.flight.arrays import indices as _indices
from emulator.flight.arrays import step_offsets_s, steps_done
from emulator.flight.autopilot import Autopilot
from emulator.flight.battery import FleetBattery
from emulator.flight.collision import ClearanceGuard
from emulator.flight.cruise import CruisePlan
from emulator.flight.dynamics import (
    CONTROL_NONE,
    CONTROL_VELOCITY,
    FleetDynamics,
    StepEvents,
    StepGuard,
)
from emulator.flight.native import (  # compiled where built (build_native.py)
    SoloBattery,
    SoloVehicle,
    cruise_plan,
    fleet_deltas,
    run_solo_steps,
)
from emulator.flight.solo import (
    ARRIVED,
    OBSTACLE_STOP,
    SOLO_EVENTS,
    TOUCHED_DOWN,
    YAW_REACHED,
)
from emulator.perception import Sensor
from emulator.scenario import Scenario
from emulator.target_motion import moving_targets_of
from emulator.truth import TruthRecorder

__all__ = ["BATTERY_EVERY_STEPS", "Fleet"]

BATTERY_EVERY_STEPS = 5  # the battery integrates at physics_hz / 5 (10 Hz at 50 Hz physics)
_NO_LEVELS = np.empty(0, dtype=np.intp)
LEAP_RETRY_STEPS = 4  # after a failed fast-forward check, step normally this many times
# At most this many vehicles are stepped one by one while the others cruise (see
# emulator.flight.cruise); with more, a plain step of the whole fleet costs less.
MAX_SOLO = 12
_NO_EVENTS = StepEvents(_NO_LEVELS, _NO_LEVELS, _NO_LEVELS, _NO_LEVELS)


class Fleet:
    """n vehicles of one scenario, stepped together at `physics_hz` of simulated time.

    Core code: no I/O and no wall clock. `step()` advances simulated time by one `dt_s`,
    moves every vehicle, drains batteries, records ground truth and hands the events of the
    step (arrivals, touchdowns, obstacle stops, battery levels, timers) to the autopilots.
    """

    def __init__(self, scenario: Scenario, *, physics_hz: float = 50.0) -> None:
        if not 5.0 <= physics_hz <= 1000.0:
            raise ValueError(f"physics_hz must be within [5, 1000], got {physics_hz}")
        specs = scenario.vehicles
        n = len(specs)
        self.scenario = scenario
        self.world = scenario.world
        self.dt_s = 1.0 / physics_hz
        # Moving targets (None without any): advanced by the physics step, sensed and recorded
        # where they are.
        self.targets = moving_targets_of(self.world.targets, self.world.obstacles)
        self.sensor = Sensor(self.world, moving=self.targets)
        self.step_count = 0
        self.battery_every_steps = BATTERY_EVERY_STEPS
        self._leap_retry_step = 0
        self._acted = False
        self.dyn = FleetDynamics(n)
        self.dyn.wind_m_s = np.asarray(self.world.wind.velocity_enu_m_s(), dtype=float)
        self.bat = FleetBattery(n)
        self.armed = np.zeros(n, dtype=bool)
        self.airborne = np.zeros(n, dtype=bool)
        self.busy = np.zeros(n, dtype=bool)
        # Vehicles whose goal ended (busy -> idle) or that a failsafe struck since the flags
        # were last cleared; `run` stops at the first such step of a vehicle in `stop_on`.
        self.ended = np.zeros(n, dtype=bool)
        self.stop_on = np.zeros(n, dtype=bool)
        self.timer_s = np.full(n, math.inf)
        self.recorder = TruthRecorder([s.id for s in specs])
        if self.targets is not None:
            self.recorder.attach_targets(self.targets)
        self.guard = ClearanceGuard(self.world, n)
        self._step_guard: StepGuard | None = self if self.guard.enabled else None
        self.fenced: tuple[int, ...] = ()  # vehicles with a fence plan (fence_changed)
        self.autopilots = [Autopilot(k, spec, self) for k, spec in enumerate(specs)]
        # Each vehicle's local frame (LOCAL_POSITION_NED, local offboard set-points): its EKF
        # origin, the ground under where it started, as every PX4 instance has its own.
        self.local_origin_m = np.array([(s.position_m[0], s.position_m[1], 0.0) for s in specs],
                                       dtype=float)
        self.index_by_id = {s.id: k for k, s in enumerate(specs)}
        self._record()

    def fence_changed(self) -> None:
        """A vehicle's fence plan changed: the vehicles with one are checked every step."""
        self.fenced = tuple(ap.k for ap in self.autopilots if ap.geofence.fenced)

    def share_local_origin(self) -> None:
        """Give every vehicle the session origin as its local origin (one shared frame)."""
        self.local_origin_m[:] = 0.0

    def local_origin(self, k: int) -> tuple[float, float, float]:
        """Vehicle k's local origin, ENU m about the session origin."""
        x, y, z = self.local_origin_m[k].tolist()
        return x, y, z

    @property
    def n(self) -> int:
        return self.dyn.n

    @property
    def now_s(self) -> float:
        return self.step_count * self.dt_s

    @property
    def any_busy(self) -> bool:
        return _any(self.busy)

    def step(self) -> None:
        """Advance simulated time by one physics step."""
        dyn = self.dyn
        events = dyn.step(self.dt_s, self._step_guard)
        if self.targets is not None:
            self.targets.advance(self.now_s, self.dt_s)
        self.step_count += 1
        levels = _NO_LEVELS
        battery_step = self.step_count % BATTERY_EVERY_STEPS == 0
        if battery_step:
            levels = self.bat.step(self.dt_s * BATTERY_EVERY_STEPS, self.airborne, self.armed,
                                   dyn.airspeed_m_s(), dyn.velocity_m_s[:, 2])
        self._record()
        self._acted = self._react(events, levels, battery_step)

    def _react(self, events: StepEvents, levels: np.ndarray, battery_step: bool) -> bool:
        """Hand the events of the step just taken to the autopilots; whether one was called
        (only they change `busy` and `ended`)."""
        aps = self.autopilots
        acted = False
        if not events.empty:
            acted = True
            for k in events.obstacle_stop:
                aps[k].on_obstacle_stop()
            for k in events.touched_down:
                aps[k].on_touchdown()
            for k in events.arrived:
                aps[k].on_arrived()
            for k in events.yaw_reached:
                aps[k].on_yaw_reached()
        if levels.size:
            acted = True
            for k in levels:
                aps[k].on_battery_level(int(self.bat.level[k]))
        by_velocity = self.dyn.control == CONTROL_VELOCITY
        if _any(by_velocity):
            acted = True
            for k in _indices(by_velocity):
                aps[k].on_velocity_step(self.dt_s)
        if self.fenced:
            for k in self.fenced:
                if self.airborne[k]:
                    acted = True
                    aps[k].geofence.check()
        if battery_step:
            charging = self.bat.charge_rate_pct_s > 0.0
            if _any(charging):
                for k in _indices(charging & (self.bat.pct >= 100.0)):
                    acted = True
                    aps[k].on_charged()
        due = _indices(self.timer_s <= self.now_s + 1e-9)
        if due.size:
            acted = True
            for k in due:
                self.timer_s[k] = math.inf
                aps[k].on_timer()
        return acted

    def due(self, active: np.ndarray) -> np.ndarray | None:
        """StepGuard: the active vehicles whose clearance the guard measures this step."""
        return self.guard.due(self.now_s + self.dt_s, active)

    def __call__(self, candidates: np.ndarray, new_pos: np.ndarray) -> np.ndarray:
        """StepGuard: the candidates whose new position lies inside an obstacle."""
        return self.guard.check(self.now_s + self.dt_s, candidates, new_pos, self.max_speed_m_s,
                                self.dt_s)

    def max_speed_m_s(self, k: int) -> float:
        """An upper bound of vehicle k's 3D speed (airspeed limit + wind + vertical rate)."""
        dyn = self.dyn
        return (dyn.airspeed_max_m_s.item(k) + dyn.wind_speed_m_s
                + max(dyn.climb_m_s.item(k), dyn.descent_m_s.item(k)))

    def mark_ended(self, k: int) -> None:
        """Vehicle k's goal was cut short by its autopilot (a failsafe took over)."""
        self.ended[k] = True

    def run(self, max_steps: int, *, fast_forward: bool = True) -> int:
        """Advance up to max_steps, fast-forwarding through steady flight; returns steps run.

        Stops early after any step in which no vehicle is busy any more, or in which a
        vehicle of `stop_on` ended its goal, so a caller in stepped mode never runs past the
        moment the swarm comes to rest or a watched vehicle needs its client's attention.
        """
        done = 0
        look = True  # the first step, and any in which an autopilot acted, can end the run
        while done < max_steps:
            was_busy = self.busy.copy()
            plan = None
            acted = False  # only autopilots change `busy`
            if fast_forward and self._leap_retry_step <= self.step_count:
                plan = cruise_plan(self, max_steps - done, max_solo=MAX_SOLO)
                if plan is None:  # not steady: do not ask again for a few steps
                    self._leap_retry_step = self.step_count + LEAP_RETRY_STEPS
            if plan is None:
                self.step()
                done += 1
                acted = self._acted
            elif plan.solo.size:
                done += self._cruise(plan)
                acted = self._acted
            else:
                self._leap(plan.steps)  # no autopilot acts in steady flight
                done += plan.steps
            if look or acted:
                if acted:
                    self.ended |= was_busy & ~self.busy
                if not _any(self.busy) or _any(self.ended & self.stop_on):
                    break
                look = False
        return done

    def _leap(self, count: int) -> None:
        """`count` steps of pure constant-velocity motion (see emulator.flight.cruise)."""
        dyn, dt = self.dyn, self.dt_s
        first = self.step_count + 1
        steps = np.arange(first, first + count)
        positions = dyn.position_m + dyn.velocity_m_s * step_offsets_s(count, dt)
        every = BATTERY_EVERY_STEPS
        first_due = -first % every  # the index of the first battery step among `steps`
        due = len(range(first_due, count, every))
        charge = self.bat.steps(due, np.array(fleet_deltas(self, dt * every)))
        # Step i records the charge after every battery step at or before it.
        battery = charge[steps_done(count, first_due, every)]
        if self.targets is not None:
            self.targets.advance(self.now_s, count * dt)
        self.step_count += count
        dyn.position_m = positions[-1].copy()
        self.recorder.record_fleet_steps(steps * dt, positions, dyn.yaw_deg, battery,
                                         self._moving_mask())

    def _cruise(self, plan: CruisePlan) -> int:
        """Up to `plan.steps` steps in which the vehicles of `plan.solo` are stepped one by
        one and every other vehicle flies at constant velocity (see emulator.flight.cruise).
        Ends after a step in which something happened to a solo vehicle (its autopilot then
        acts, as after a plain step) or once every solo vehicle flies steadily after speeding
        up, braking or turning; returns the steps run."""
        dyn, dt, bat, n = self.dyn, self.dt_s, self.bat, self.n
        guard = _SoloGuard(self) if self.guard.enabled else None
        rows: list[float] = []  # x, y, z, yaw, moving of each solo vehicle, step by step
        ks, states = plan.solo.tolist(), plan.states
        solos = ([SoloVehicle(dyn, k, dt, guard, rows) for k in ks] if states is None else
                 [SoloVehicle(dyn, k, dt, guard, rows, state)
                  for k, state in zip(ks, states, strict=True)])
        moving = self._moving_mask()
        start = self.step_count
        battery = SoloBattery(self, plan.solo, dt * BATTERY_EVERY_STEPS)
        charge: list[list[float]] = [battery.pct]  # then the charges after each battery step
        bits = [0] * len(solos)
        first_battery = BATTERY_EVERY_STEPS - start % BATTERY_EVERY_STEPS
        j, battery_step = run_solo_steps(
            solos, bits, plan.steps, start, dt, first_battery, BATTERY_EVERY_STEPS, battery,
            charge, LEAP_RETRY_STEPS)
        if battery.ran:
            bat.pct = np.array(battery.pct)
        steps = np.arange(start + 1, start + j + 1)
        positions = dyn.position_m + dyn.velocity_m_s * step_offsets_s(j, dt)
        solo_rows = np.fromiter(rows, float, len(rows)).reshape(j, len(solos), 5)
        index = plan.solo
        positions[:, index] = solo_rows[:, :, :3]
        yaw = np.empty((j, n))
        yaw[:] = dyn.yaw_deg
        yaw[:, index] = solo_rows[:, :, 3]
        moving_rows = np.empty((j, n), dtype=bool)
        moving_rows[:] = moving
        moving_rows[:, index] = solo_rows[:, :, 4] != 0.0
        if self.targets is not None:
            self.targets.advance(self.now_s, j * dt)
        self.step_count += j
        dyn.position_m = positions[-1].copy()
        yaw_step = np.zeros(n)
        for solo in solos:
            solo.store(dyn)
            yaw_step[solo.k] = solo.yaw_step
        dyn.yaw_step_deg = yaw_step
        # Step i records the charge after every battery step at or before it (the battery
        # steps are first_battery, first_battery + BATTERY_EVERY_STEPS, ... after start).
        done = steps_done(j, first_battery - 1, BATTERY_EVERY_STEPS)
        self.recorder.record_fleet_steps(steps * dt, positions, yaw, np.array(charge)[done],
                                         moving_rows)
        events = _NO_EVENTS
        if any(b & SOLO_EVENTS for b in bits):
            events = StepEvents(*(np.array([s.k for s, b in zip(solos, bits, strict=True)
                                            if b & bit], dtype=np.intp)
                                  for bit in (ARRIVED, YAW_REACHED, TOUCHED_DOWN, OBSTACLE_STOP)))
        self._acted = self._react(events, battery.levels if battery_step else _NO_LEVELS,
                                  battery_step)
        return j

    def _moving_mask(self) -> np.ndarray:
        dyn = self.dyn
        return (dyn.control != CONTROL_NONE) & (dyn.velocity_m_s.any(axis=1) | dyn.yaw_tracking)

    def _record(self) -> None:
        dyn = self.dyn
        self.recorder.record_fleet_step(self.now_s, dyn.position_m, dyn.yaw_deg, self.bat.pct,
                                        self._moving_mask())


class _SoloGuard:
    """The fleet's clearance guard for vehicles stepped one by one (emulator.flight.solo)."""

    def __init__(self, fleet: Fleet) -> None:
        self._fleet = fleet
        self._guard = fleet.guard

    def __call__(self, k: int, t_s: float, x_m: float, y_m: float, z_m: float) -> bool:
        fleet = self._fleet
        return self._guard.check_one(k, t_s, x_m, y_m, z_m, fleet.max_speed_m_s(k), fleet.dt_s)

    def check_at_s(self, k: int) -> float:
        return float(self._guard.check_at_s[k])
