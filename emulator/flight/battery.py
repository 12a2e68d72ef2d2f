"""Vectorised battery model: charge drains with flight time and effort.

Drain in percent per second is ``100 / hover_endurance_s * power_factor`` where the power
factor grows with airspeed (so a headwind costs more than a tailwind) and with climb rate.
Armed on the ground the motors idle at a small fraction of hover power. Fixed costs per
photo are charged through :meth:`FleetBattery.spend`. A vehicle resting disarmed on a charging
station gains charge at the station's rate.
"""

from __future__ import annotations

from typing import Final

import numpy as np

from emulator.flight.arrays import count_nonzero as _count
from emulator.flight.arrays import indices as _indices

__all__ = [
    "BATTERY_CRITICAL",
    "BATTERY_EMERGENCY",
    "BATTERY_LOW",
    "BATTERY_OK",
    "CLIMB_POWER_PER_M_S",
    "GROUND_IDLE_POWER",
    "MESSAGE_COST_PCT",
    "PHOTO_COST_PCT",
    "SPEED_POWER_PER_M2_S2",
    "FleetBattery",
    "cell_voltage_v",
    "power_factor",
]

SPEED_POWER_PER_M2_S2: Final = 0.004  # +0.4 % power per (m/s)^2 of airspeed: +40 % at 10 m/s
CLIMB_POWER_PER_M_S: Final = 0.08  # +8 % power per m/s of climb
GROUND_IDLE_POWER: Final = 0.1  # armed on the ground: motors idle at 10 % of hover power
PHOTO_COST_PCT = 0.05
MESSAGE_COST_PCT = 0.01  # per message sent (a broadcast counts once)

BATTERY_OK, BATTERY_LOW, BATTERY_CRITICAL, BATTERY_EMERGENCY = 0, 1, 2, 3
_NO_CHANGE = np.empty(0, dtype=np.intp)
_min, _max = np.minimum.reduce, np.maximum.reduce


class FleetBattery:
    """Charge state of n vehicles in percent, with PX4's low/critical/emergency levels."""

    def __init__(self, n: int) -> None:
        self.pct = np.full(n, 100.0)
        self.hover_endurance_s = np.full(n, 1200.0)
        # The rows low, critical, emergency and empty (0 %) of one array: `levels_pct`.
        self.levels_pct = np.zeros((4, n))
        self.low_pct, self.critical_pct, self.emergency_pct = self.levels_pct[:3]
        self.low_pct[:] = 15.0
        self.critical_pct[:] = 7.0
        self.emergency_pct[:] = 5.0
        self.charge_rate_pct_s = np.zeros(n)  # > 0 while resting on a charging station
        self.level = np.zeros(n, dtype=np.int8)

    def drain_pct_s(self, airborne: np.ndarray, armed: np.ndarray, airspeed_m_s: np.ndarray,
                    climb_m_s: np.ndarray) -> np.ndarray:
        """Discharge rate of every vehicle in percent per second (before charging)."""
        power = np.where(airborne, power_factor(airspeed_m_s, climb_m_s),
                         np.where(armed, GROUND_IDLE_POWER, 0.0))
        return (100.0 / self.hover_endurance_s) * power

    def step(
        self,
        dt_s: float,
        airborne: np.ndarray,
        armed: np.ndarray,
        airspeed_m_s: np.ndarray,
        climb_m_s: np.ndarray,
    ) -> np.ndarray:
        """Drain (or charge) for dt_s; returns indices whose level changed."""
        return self.apply(self.deltas(dt_s, airborne, armed, airspeed_m_s, climb_m_s))

    def deltas(self, dt_s: float, airborne: np.ndarray, armed: np.ndarray,
               airspeed_m_s: np.ndarray, climb_m_s: np.ndarray) -> np.ndarray:
        """The change of charge of every vehicle over a `step` of dt_s (before clipping)."""
        rate = self.drain_pct_s(airborne, armed, airspeed_m_s, climb_m_s)
        return (self.charge_rate_pct_s - rate) * dt_s

    def delta(self, k: int, dt_s: float, airborne: bool, armed: bool, airspeed_m_s: float,
              climb_m_s: float) -> float:
        """`deltas` of vehicle k alone, in Python floats (the same operations)."""
        if airborne:
            power = (1.0 + SPEED_POWER_PER_M2_S2 * (airspeed_m_s * airspeed_m_s)
                     + CLIMB_POWER_PER_M_S * max(climb_m_s, 0.0))
        else:
            power = GROUND_IDLE_POWER if armed else 0.0
        rate = 100.0 / float(self.hover_endurance_s[k]) * power
        return (float(self.charge_rate_pct_s[k]) - rate) * dt_s

    def apply(self, delta: np.ndarray) -> np.ndarray:
        """Add delta to every charge (clipped to 0-100 %); returns indices whose level
        changed."""
        self.pct = np.minimum(np.maximum(self.pct + delta, 0.0), 100.0)
        return self._update_levels()

    def set_pct(self, pct: np.ndarray) -> np.ndarray:
        """Replace every charge (already within 0-100 %); returns indices whose level
        changed."""
        self.pct = pct
        return self._update_levels()

    def steps(self, count: int, delta: np.ndarray) -> np.ndarray:
        """`count` calls of `step` with the same inputs (steady flight), at once, given their
        `deltas`; returns the charge before and after each, (count + 1, n). Level changes are
        not reported (the levels are brought up to date)."""
        charge = np.empty((count + 1, self.pct.size))
        charge[0] = self.pct
        charge[1:] = delta
        np.add.accumulate(charge, axis=0, out=charge)  # the same sums, one after the other
        after = charge[1:]
        size = after.size
        if _count(after > 0.0) != size or _count(after <= 100.0) != size:  # clipped: one by one
            for i in range(1, count + 1):
                charge[i] = np.minimum(np.maximum(charge[i - 1] + delta, 0.0), 100.0)
        if count:
            self.pct = charge[-1].copy()
            self._update_levels()
        return charge

    def spend(self, k: int, pct: float) -> None:
        self.pct[k] = max(0.0, self.pct[k] - pct)

    def _update_levels(self) -> np.ndarray:
        pct = self.pct
        if not _count(self.level) and _min(pct) > _max(self.levels_pct, axis=None):
            return _NO_CHANGE  # every charge above every level, and every level already OK
        level = (pct <= self.low_pct).view(np.int8) + (pct <= self.critical_pct).view(np.int8)
        level += (pct <= self.emergency_pct).view(np.int8)
        changed = _indices(level != self.level)
        self.level = level
        return changed


def power_factor(airspeed_m_s: np.ndarray, climb_m_s: np.ndarray) -> np.ndarray:
    """Electrical power relative to hover, from airspeed and climb rate."""
    return 1.0 + SPEED_POWER_PER_M2_S2 * airspeed_m_s**2 + CLIMB_POWER_PER_M_S * np.maximum(
        climb_m_s, 0.0)


def cell_voltage_v(pct: float, empty_v: float, full_v: float) -> float:
    """Open-circuit cell voltage for a charge level (a linear curve between empty and full)."""
    return empty_v + (full_v - empty_v) * max(0.0, min(100.0, pct)) / 100.0
