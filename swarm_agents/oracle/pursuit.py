"""Where a moving target will be, for the oracle: the world's hidden motion, replayed exactly
(emulator.target_motion) from the session's start."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from emulator.target_motion import MovingTargets, moving_targets_of
from emulator.world import World

__all__ = ["HORIZON_S", "Pursuit"]

HORIZON_S = 1800.0  # how far ahead a meeting is looked for
_SCAN_S = 0.5
_ZONE_MARGIN_M = 3.0


class Pursuit:
    """Predictions of one world's moving targets."""

    def __init__(self, world: World) -> None:
        self._moving: MovingTargets | None = moving_targets_of(world.targets, world.obstacles)

    def xy(self, target_id: str, t_s: float) -> tuple[float, float]:
        if self._moving is None:
            raise KeyError(f"no moving target {target_id!r}")
        p = self._moving.legs(target_id).positions(np.array([t_s]))[0]
        return float(p[0]), float(p[1])

    def meeting(self, target_id: str, now_s: float,
                flight_s: Callable[[tuple[float, float]], float],
                lower_s: Callable[[tuple[float, float]], float],
                zone: tuple[float, float, float] | None = None) -> float:
        """The earliest time t at which a drone that needs flight_s(point) to reach a point
        can be at the target's position at t (inside the zone when given, keeping a margin
        from its edge); lower_s is a cheap lower bound of flight_s."""
        if self._moving is None:
            raise KeyError(f"no moving target {target_id!r}")
        legs = self._moving.legs(target_id)
        times = now_s + np.arange(0.0, HORIZON_S, _SCAN_S)
        xyz = legs.positions(times)
        ok = np.ones(times.size, dtype=bool)
        if zone is not None:
            zx, zy, zr = zone
            inside = np.hypot(xyz[:, 0] - zx, xyz[:, 1] - zy) <= max(zr - _ZONE_MARGIN_M,
                                                                      zr / 2.0)
            ok &= inside
        candidates = np.flatnonzero(ok)
        for k in candidates:
            t, point = float(times[k]), (float(xyz[k, 0]), float(xyz[k, 1]))
            if now_s + lower_s(point) <= t and now_s + flight_s(point) <= t:
                return t
        raise ValueError(f"target {target_id} cannot be met within {HORIZON_S:g} s")
