"""What a check tree is evaluated on: the ground truth of one task's time window.

:class:`CheckContext` also caches per-drone derived data (clipped trajectories, flight paths,
coverage corridors) so that the leaves of one tree share the work.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np

from benchmark.scoring.validators._errors import EvaluationError
from benchmark.scoring.validators.track import Track, build_track
from emulator.scenario import Scenario, VehicleSpec
from emulator.truth import TruthEvent, TruthHistory
from emulator.truth_events import TruthEventKind
from emulator.world import Obstacle, Target

__all__ = ["AIRBORNE_M", "RECENT_S", "CheckContext", "DroneState"]

AIRBORNE_M = 1.0
"""A drone is airborne at altitude z >= AIRBORNE_M."""
RECENT_S = 0.05
"""Current-state checks judge hovering by the speed over the last RECENT_S seconds."""

T = TypeVar("T")


@dataclass(frozen=True, slots=True)
class DroneState:
    """A drone's state at the end of the window."""

    xyz_m: tuple[float, float, float]
    yaw_deg: float
    battery_pct: float
    speed_m_s: float
    recent_max_speed_m_s: float

    @property
    def airborne(self) -> bool:
        return self.xyz_m[2] >= AIRBORNE_M


@dataclass(frozen=True)
class CheckContext:
    """Ground truth of the window [t0_s, t1_s]; current-state checks look at the instant t1_s."""

    history: TruthHistory
    scenario: Scenario
    t0_s: float
    t1_s: float
    _cache: dict[tuple[Any, ...], Any] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        for name in ("t0_s", "t1_s"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f"CheckContext.{name} must be a number, got {value!r}")
            if not math.isfinite(value):
                raise ValueError(f"CheckContext.{name} must be finite, got {value!r}")
            object.__setattr__(self, name, float(value))
        if self.t1_s < self.t0_s:
            raise ValueError(f"CheckContext window is empty: t1_s={self.t1_s} < t0_s={self.t0_s}")

    def cached(self, key: tuple[Any, ...], make: Callable[[], T]) -> T:
        """The value stored under key, computed with make() on first use."""
        try:
            return self._cache[key]
        except KeyError:
            value = self._cache[key] = make()
            return value

    # ------------------------------------------------------------------ entities
    @property
    def drone_ids(self) -> tuple[str, ...]:
        return tuple(v.id for v in self.scenario.vehicles)

    def vehicle(self, drone_id: str) -> VehicleSpec:
        table = self.cached(("vehicles",), lambda: {v.id: v for v in self.scenario.vehicles})
        if drone_id not in table:
            raise EvaluationError(f"drone {drone_id!r} is not in scenario {self.scenario.name!r}")
        return table[drone_id]

    def target(self, target_id: str) -> Target:
        try:
            return self.scenario.world.target(target_id)
        except KeyError:
            raise EvaluationError(
                f"target {target_id!r} is not in scenario {self.scenario.name!r}") from None

    def obstacle(self, obstacle_id: str) -> Obstacle:
        try:
            return self.scenario.world.obstacle(obstacle_id)
        except KeyError:
            raise EvaluationError(
                f"obstacle {obstacle_id!r} is not in scenario {self.scenario.name!r}") from None

    # ------------------------------------------------------------------ truth
    def track(self, drone_id: str, a_s: float, b_s: float) -> Track:
        """The drone's truth clipped to [a_s, b_s] (see :func:`build_track`)."""
        self.vehicle(drone_id)
        if drone_id not in self.history.vehicle_ids:
            raise EvaluationError(f"the ground truth has no record of drone {drone_id!r}")
        return self.cached(("track", drone_id, a_s, b_s),
                           lambda: build_track(self.history, drone_id, a_s, b_s))

    def window(self, drone_id: str) -> Track:
        """The drone's truth over the whole window [t0_s, t1_s]."""
        return self.track(drone_id, self.t0_s, self.t1_s)

    def state(self, drone_id: str) -> DroneState:
        """The drone's state at t1_s; EvaluationError when nothing was recorded by then."""
        def make() -> DroneState:
            recent = self.track(drone_id, self.t1_s - RECENT_S, self.t1_s)
            if recent.empty:
                raise EvaluationError(
                    f"no ground-truth samples for drone {drone_id!r} at or before "
                    f"t={self.t1_s:g} s")
            x, y, z = (float(v) for v in recent.xyz_m[-1])
            return DroneState((x, y, z), float(recent.yaw_deg[-1] % 360.0),
                              float(recent.battery_pct[-1]), recent.last_speed_m_s(),
                              recent.max_speed_m_s())
        return self.cached(("state", drone_id), make)

    def events(self, drone_id: str, kinds: Iterable[TruthEventKind]) -> list[TruthEvent]:
        """The drone's events of the given kinds inside the window, in recording order."""
        self.vehicle(drone_id)
        if drone_id not in self.history.vehicle_ids:
            raise EvaluationError(f"the ground truth has no record of drone {drone_id!r}")
        return self.history.events(drone_id, self.t0_s, self.t1_s, kinds=tuple(kinds))

    def home_at(self, drone_id: str, t_s: float) -> tuple[float, float, float]:
        """position_m of the drone's last ``home`` event at or before t_s, else its spec home."""
        spec = self.vehicle(drone_id)
        if drone_id in self.history.vehicle_ids:
            homes = self.history.events(drone_id, None, t_s, kinds=(TruthEventKind.HOME,))
            if homes:
                x, y, z = (float(v) for v in homes[-1].data["position_m"])
                return x, y, z
        return spec.home_m

    def battery_at(self, drone_id: str, t_s: float, *, before: bool = False) -> float:
        """Battery at t_s interpolated from the window's truth; with ``before``, the value
        held just before t_s (rows at exactly t_s are ignored)."""
        track = self.window(drone_id)
        if track.empty:
            raise EvaluationError(f"no ground-truth samples for drone {drone_id!r} in the window")
        if before:
            k = int(np.searchsorted(track.t_s, t_s, side="left")) - 1
            return float(track.battery_pct[max(k, 0)])
        return float(np.interp(t_s, track.t_s, track.battery_pct))
