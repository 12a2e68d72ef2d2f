"""What an autopilot (and the fast-forward check) uses of its fleet: the shared arrays, the
world, the truth recorder, simulated time.

emulator.flight.fleet.Fleet is the one implementation; the autopilot, its parts and
emulator.flight.cruise name this protocol instead, so that the fleet may import them without
an import circle.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from emulator.flight.battery import FleetBattery
from emulator.flight.collision import ClearanceGuard
from emulator.flight.dynamics import FleetDynamics
from emulator.perception import Sensor
from emulator.truth import TruthRecorder
from emulator.world import World

__all__ = ["FleetView"]


class FleetView(Protocol):
    """The fleet as one of its autopilots sees it (every member is read-only here; the
    arrays are written element by element, never replaced)."""

    @property
    def dyn(self) -> FleetDynamics: ...
    @property
    def bat(self) -> FleetBattery: ...
    @property
    def armed(self) -> np.ndarray: ...
    @property
    def airborne(self) -> np.ndarray: ...
    @property
    def busy(self) -> np.ndarray: ...
    @property
    def timer_s(self) -> np.ndarray: ...
    @property
    def world(self) -> World: ...
    @property
    def sensor(self) -> Sensor: ...
    @property
    def guard(self) -> ClearanceGuard: ...
    @property
    def recorder(self) -> TruthRecorder: ...
    @property
    def index_by_id(self) -> dict[str, int]: ...
    @property
    def step_count(self) -> int: ...
    @property
    def dt_s(self) -> float: ...
    @property
    def battery_every_steps(self) -> int: ...
    @property
    def now_s(self) -> float: ...
    @property
    def local_origin_m(self) -> np.ndarray: ...
    def local_origin(self, k: int) -> tuple[float, float, float]: ...
    def mark_ended(self, k: int) -> None: ...
