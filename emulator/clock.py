"""The simulated clock: fixed physics steps, paced in real time or stepped on demand.

Simulated time is `steps * dt_s`, so it never drifts. Two pacing modes:

- real time x speed: steps run as wall time passes, `speed` times faster; if the machine
  cannot keep up, the clock slips (the real-time factor drops) instead of bursting;
- stepped: simulated time advances only while some vehicle is executing a goal, or while a
  caller has asked the clock to advance. A client's think time costs nothing while the swarm
  is at rest, but other vehicles' goals run on while it thinks;
- lockstep (stepped, plus): simulated time advances only while every client waits on the
  world (see emulator.lockstep); the clock stops wherever a watched vehicle needs its client,
  so results never depend on how long clients think or how loaded the machine is.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["ClockConfig", "RealTimePacer"]


@dataclass(frozen=True, slots=True)
class ClockConfig:
    """How simulated time is paced."""

    physics_hz: float = 50.0
    speed: float = 1.0
    stepped: bool = False
    lockstep: bool = False

    def __post_init__(self) -> None:
        if not (math.isfinite(self.physics_hz) and 5.0 <= self.physics_hz <= 1000.0):
            raise ValueError(f"physics_hz must be within [5, 1000], got {self.physics_hz}")
        if not (math.isfinite(self.speed) and 0.01 <= self.speed <= 10000.0):
            raise ValueError(f"speed must be within [0.01, 10000], got {self.speed}")
        if self.stepped and self.speed != 1.0:
            raise ValueError("speed applies to real-time pacing; stepped mode runs flat out")
        if self.lockstep and not self.stepped:
            raise ValueError("lockstep pacing is a stepped clock: set stepped too")

    @property
    def dt_s(self) -> float:
        return 1.0 / self.physics_hz


class RealTimePacer:
    """How many physics steps are due at a given wall time, at `speed` x real time."""

    def __init__(self, config: ClockConfig, wall_now_s: float, *, max_lag_s: float = 0.25):
        self.dt_s = config.dt_s
        self.speed = config.speed
        self._wall0_s = wall_now_s
        self._steps0 = 0
        self._max_steps = max(1, int(max_lag_s * self.speed / self.dt_s))
        self.slipped_s = 0.0  # simulated time the clock gave up on because the host was slow

    def next_step_wall_s(self, steps_done: int) -> float:
        """The wall time at which one more step than `steps_done` becomes due."""
        return self._wall0_s + (steps_done + 1 - self._steps0) * self.dt_s / self.speed

    def steps_due(self, wall_now_s: float, steps_done: int) -> int:
        target = int((wall_now_s - self._wall0_s) * self.speed / self.dt_s) + self._steps0
        due = target - steps_done
        if due > self._max_steps:
            self.slipped_s += (due - self._max_steps) * self.dt_s
            self._steps0 -= due - self._max_steps
            due = self._max_steps
        return max(0, due)
