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

__all__ = ["NO_LEVELS", "SoloBattery", "fleet_deltas"]

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
            inputs = _DrainInputs(self._fleet)
            deltas = self._deltas = inputs.deltas(self._dt_s)
            self._flags = [(inputs.airborne[k], inputs.armed[k], inputs.full_pct_s[k],
                            inputs.charge_pct_s[k]) for k in self._solo.tolist()]
        wind_x, wind_y, dt_s = self._wind_x, self._wind_y, self._dt_s
        for vehicle, (airborne, armed, full_pct_s, charge_pct_s) in zip(
                solos, self._flags, strict=True):
            # FleetBattery.delta, written out
            air = _hypot(vehicle.vx - wind_x, vehicle.vy - wind_y) if airborne else 0.0
            power = _power(airborne, armed, air, vehicle.vz)
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


def fleet_deltas(fleet: FleetView, dt_s: float) -> list[float]:
    """FleetBattery.deltas(dt_s, airborne, armed, dyn.airspeed_m_s(), vz) of every vehicle in
    Python floats, one vehicle after the other: the same operations in the same order (the
    airspeed is numpy's hypot, as there), so the same values to the last bit, for a fraction
    of the calls into numpy."""
    return _DrainInputs(fleet).deltas(dt_s)


class _DrainInputs:
    """What FleetBattery.deltas reads, as Python lists."""

    def __init__(self, fleet: FleetView) -> None:
        bat, dyn = fleet.bat, fleet.dyn
        self.air: list[float] = dyn.airspeed_m_s().tolist()
        self.climb: list[float] = dyn.velocity_m_s[:, 2].tolist()
        self.full_pct_s: list[float] = (100.0 / bat.hover_endurance_s).tolist()
        self.charge_pct_s: list[float] = bat.charge_rate_pct_s.tolist()
        self.airborne: list[bool] = fleet.airborne.tolist()
        self.armed: list[bool] = fleet.armed.tolist()

    def deltas(self, dt_s: float) -> list[float]:
        air, climb, airborne, armed = self.air, self.climb, self.airborne, self.armed
        full_pct_s, charge_pct_s = self.full_pct_s, self.charge_pct_s
        return [(charge_pct_s[k] - full_pct_s[k] * _power(airborne[k], armed[k], air[k], climb[k]))
                * dt_s for k in range(len(air))]


def _power(airborne: bool, armed: bool, air_m_s: float, vz_m_s: float) -> float:
    """FleetBattery.drain_pct_s' power factor of one vehicle: battery.power_factor in the air
    (`max(vz, 0.0)` keeps a NaN and -0.0 as np.maximum does), idle power armed on the ground."""
    if airborne:
        return (1.0 + SPEED_POWER_PER_M2_S2 * (air_m_s * air_m_s)
                + CLIMB_POWER_PER_M_S * max(vz_m_s, 0.0))
    return GROUND_IDLE_POWER if armed else 0.0


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
