"""The fleet's batteries while a few vehicles are stepped one by one (emulator.flight.solo).

Every battery step of a cruise with solo vehicles works in Python floats, with the operations of
FleetBattery.deltas and apply: the cruising vehicles keep the change of charge they had at the
start (their speed does not change), the solo vehicles' is worked out from their new velocity.
The battery levels are worked out by the battery itself unless every charge lies above every
level and every level is OK.
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np

from emulator.flight.arrays import any_true, count_nonzero, indices
from emulator.flight.battery import (
    CLIMB_POWER_PER_M_S,
    GROUND_IDLE_POWER,
    SPEED_POWER_PER_M2_S2,
)
from emulator.flight.fleet_view import FleetView
from emulator.flight.solo import SoloVehicle

__all__ = ["NO_LEVELS", "SoloBattery"]

NO_LEVELS = np.empty(0, dtype=np.intp)
_hypot: Final = math.hypot  # bound once (see emulator.flight.solo)


class SoloBattery:
    """`pct`: every vehicle's charge after the last battery step (a new list at each);
    `levels`: the vehicles whose level changed at it; `ran`: whether one ran."""

    def __init__(self, fleet: FleetView, solo: np.ndarray, dt_s: float) -> None:
        """solo: the indices of the vehicles stepped one by one; dt_s: a battery step."""
        bat = fleet.bat
        self._fleet, self._bat, self._solo, self._dt_s = fleet, bat, solo, dt_s
        charging = bat.charge_rate_pct_s > 0.0
        self._any_charging = any_true(charging)
        self._charging_k: list[int] = indices(charging).tolist()
        self._deltas: list[float] | None = None  # per battery step (the same for the cruising)
        # airborne, armed, full charge per s of hover (%/s) and charge rate of each solo vehicle
        self._flags: list[tuple[bool, bool, float, float]] = []
        self._floor_pct = float(bat.levels_pct.max())
        self._levels_ok = not count_nonzero(bat.level)  # every vehicle's level OK (kept below)
        wind: list[float] = fleet.dyn.wind_m_s.tolist()  # typed: C doubles when compiled
        self._wind_x: float = wind[0]
        self._wind_y: float = wind[1]
        self.pct: list[float] = bat.pct.tolist()
        self.levels = NO_LEVELS
        self.ran = False

    def step(self, solos: list[SoloVehicle]) -> bool:
        """One battery step; whether the autopilots must look at the fleet after it (a level
        changed, or a charging vehicle is full)."""
        self.ran = True
        bat = self._bat
        deltas = self._deltas
        if deltas is None:
            fleet, dyn = self._fleet, self._fleet.dyn
            deltas = self._deltas = bat.deltas(self._dt_s, fleet.airborne, fleet.armed,
                                               dyn.airspeed_m_s(),
                                               dyn.velocity_m_s[:, 2]).tolist()
            solo = self._solo
            self._flags = list(zip(fleet.airborne[solo].tolist(), fleet.armed[solo].tolist(),
                                   (100.0 / bat.hover_endurance_s[solo]).tolist(),
                                   bat.charge_rate_pct_s[solo].tolist(), strict=True))
        wind_x, wind_y, dt_s = self._wind_x, self._wind_y, self._dt_s
        for vehicle, (airborne, armed, full_pct_s, charge_pct_s) in zip(
                solos, self._flags, strict=True):
            # FleetBattery.delta, written out
            if airborne:
                air = _hypot(vehicle.vx - wind_x, vehicle.vy - wind_y)
                power = (1.0 + SPEED_POWER_PER_M2_S2 * (air * air)
                         + CLIMB_POWER_PER_M_S * max(vehicle.vz, 0.0))
            else:
                power = GROUND_IDLE_POWER if armed else 0.0
            deltas[vehicle.k] = (charge_pct_s - full_pct_s * power) * dt_s
        before = self.pct
        pct = [before[i] + deltas[i] for i in range(len(before))]
        lowest, highest = _bounds(pct)
        if lowest < 0.0 or highest > 100.0:
            pct = [_clip_pct(p) for p in pct]
            lowest = _bounds(pct)[0]
        self.pct = pct
        if lowest > self._floor_pct and self._levels_ok:
            self.levels = NO_LEVELS
        else:
            self.levels = bat.set_pct(np.array(pct))
            self._levels_ok = not count_nonzero(bat.level)
        return bool(self.levels.size) or (
            self._any_charging and any(pct[k] >= 100.0 for k in self._charging_k))


def _bounds(values: list[float]) -> tuple[float, float]:
    """min(values) and max(values) of a non-empty list, in one compiled pass."""
    lowest = highest = values[0]
    for value in values:
        if value < lowest:
            lowest = value
        elif value > highest:
            highest = value
    return lowest, highest


def _clip_pct(pct: float) -> float:
    """np.minimum(np.maximum(pct, 0.0), 100.0) for one float (FleetBattery.apply)."""
    pct = 0.0 if pct < 0.0 else pct
    return 100.0 if pct > 100.0 else pct
