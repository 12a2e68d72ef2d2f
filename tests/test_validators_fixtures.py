"""Builders shared by the validator tests: small scenarios and hand-made 50 Hz ground truth.

Test modules import what they use; the tests here check the builders themselves.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pytest

from benchmark.scoring.validators import CheckContext, LeafResult, evaluate, parse_tree
from emulator.scenario import Scenario
from emulator.truth import TruthEvent, TruthHistory, TruthLog

__all__ = [
    "DT_S",
    "check",
    "context",
    "event",
    "lawnmower",
    "log",
    "rows",
]

DT_S = 0.02


def rows(keyframes: Sequence[Sequence[float]], *, t_end_s: float | None = None,
         dt_s: float = DT_S, battery: tuple[float, float] = (100.0, 0.0),
         yaw_deg: float = 0.0) -> np.ndarray:
    """Truth rows every dt_s along the piecewise-linear path through keyframes (t, x, y, z).

    battery = (start %, drain % per second); the path holds its last point until t_end_s.
    """
    key = np.asarray(keyframes, dtype=float).reshape(-1, 4)
    t0 = key[0, 0]
    t1 = key[-1, 0] if t_end_s is None else t_end_s
    t = t0 + dt_s * np.arange(round((t1 - t0) / dt_s) + 1)
    out = np.empty((t.size, 6))
    out[:, 0] = t
    for axis in range(3):
        out[:, 1 + axis] = np.interp(t, key[:, 0], key[:, 1 + axis])
    out[:, 4] = yaw_deg
    out[:, 5] = np.clip(battery[0] - battery[1] * (t - t0), 0.0, 100.0)
    return out


def lawnmower(x0: float, y0: float, x1: float, y1: float, spacing_m: float, *, z_m: float,
              speed_m_s: float, t0_s: float = 0.0) -> list[tuple[float, float, float, float]]:
    """Keyframes of a boustrophedon over the rectangle, legs along x, spacing_m apart in y."""
    points: list[tuple[float, float]] = []
    y, leftwards = y0, False
    while y <= y1 + 1e-9:
        xs = (x1, x0) if leftwards else (x0, x1)
        points += [(xs[0], y), (xs[1], y)]
        y += spacing_m
        leftwards = not leftwards
    keyframes = [(t0_s, points[0][0], points[0][1], z_m)]
    for (ax, ay), (bx, by) in itertools.pairwise(points):
        keyframes.append((keyframes[-1][0] + np.hypot(bx - ax, by - ay) / speed_m_s, bx, by,
                          z_m))
    return keyframes


def event(t_s: float, vehicle_id: str, kind: str, **data: Any) -> TruthEvent:
    return TruthEvent(t_s, vehicle_id, kind, data)


def log(trajectories: Mapping[str, np.ndarray], events: Sequence[TruthEvent] = (),
        *, end_t_s: float | None = None) -> TruthLog:
    """A truth log with the given rows per drone; end_t_s defaults to the latest row."""
    ids = list(trajectories)
    latest = max((float(r[-1, 0]) for r in trajectories.values() if len(r)), default=np.nan)
    return TruthLog(ids, [trajectories[i] for i in ids], events,
                    end_t_s=latest if end_t_s is None else end_t_s)


def context(history: TruthHistory, scen: Scenario, t0_s: float, t1_s: float) -> CheckContext:
    return CheckContext(history, scen, t0_s, t1_s)


def check(ctx: CheckContext, endpoint: str, expect: bool = True, **parameters: Any
          ) -> LeafResult:
    """Parse one leaf against the context's scenario and evaluate it."""
    tree = parse_tree({"endpoint": endpoint, "parameters": parameters, "expect": expect},
                      ctx.scenario)
    (leaf,) = evaluate(tree, ctx).leaves
    return leaf


def test_rows_follow_the_keyframes_at_50_hz() -> None:
    r = rows([(0.0, 0.0, 0.0, 0.0), (1.0, 10.0, 0.0, 5.0)], t_end_s=2.0, battery=(90.0, 1.0))
    assert r.shape == (101, 6)
    assert r[25, 1:4] == pytest.approx((5.0, 0.0, 2.5))
    assert r[-1, 1:4] == pytest.approx((10.0, 0.0, 5.0))
    assert r[-1, 5] == pytest.approx(88.0)


def test_lawnmower_legs_alternate_and_keep_speed() -> None:
    keys = lawnmower(0.0, 0.0, 100.0, 20.0, 10.0, z_m=10.0, speed_m_s=10.0)
    assert [(k[1], k[2]) for k in keys] == [(0, 0), (100, 0), (100, 10), (0, 10), (0, 20),
                                            (100, 20)]
    assert keys[-1][0] == pytest.approx(32.0)
