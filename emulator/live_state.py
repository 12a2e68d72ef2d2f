"""Every vehicle's state now, compactly, for live views (the web console): simulated time and,
per vehicle in scenario order, position, heading, speed, battery, armed and flight mode. Ground
truth: for operators' views, never for agents."""

from __future__ import annotations

from typing import Any

import numpy as np

from emulator.flight.fleet import Fleet

__all__ = ["live_state"]


def _rounded(values: np.ndarray, digits: int) -> list[float]:
    return [float(v) for v in np.round(values, digits)]


def live_state(fleet: Fleet) -> dict[str, Any]:
    """The fleet's state as JSON-ready lists (metres, degrees, m/s, percent)."""
    dyn = fleet.dyn
    pos = dyn.position_m
    return {"t": round(fleet.now_s, 2), "x": _rounded(pos[:, 0], 2),
            "y": _rounded(pos[:, 1], 2), "z": _rounded(pos[:, 2], 2),
            "yaw": _rounded(dyn.yaw_deg, 1),
            "spd": _rounded(np.linalg.norm(dyn.velocity_m_s, axis=1), 2),
            "bat": _rounded(fleet.bat.pct, 1), "armed": fleet.armed.astype(int).tolist(),
            "mode": [ap.mode.label for ap in fleet.autopilots]}
