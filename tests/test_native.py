"""The compiled hot path (build_native.py, emulator.flight.native): used only when built from the
sources in the tree, and the same results as the pure-Python modules to the last bit."""

from __future__ import annotations

import copy
import hashlib
import importlib
import json
import logging
import math
import os
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest

from emulator.flight import cruise, native, solo
from emulator.flight.dynamics import DEG_PER_RAD
from tests.test_solo_step import DT_S, _random_dynamics

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
import build_native  # noqa: E402  (the build script at the root of the tree)


def _built(name: str) -> types.ModuleType:
    if build_native.is_stale(name):
        pytest.skip(f"emulator/flight/{name}.py has no up-to-date compiled build here "
                    "(`python build_native.py` makes one; it needs a C compiler)")
    return importlib.import_module(f"emulator.flight._{name}_native")


@pytest.mark.parametrize("name", build_native.NATIVE)
def test_a_fresh_build_is_the_one_used(name: str) -> None:
    module = _built(name)
    source = (ROOT / "emulator" / "flight" / f"{name}.py").read_bytes()
    assert hashlib.sha256(source).hexdigest() == module.SOURCE_SHA256
    assert name in native.COMPILED
    assert native.compiled(name) is module


def test_a_stale_build_is_not_used(monkeypatch: pytest.MonkeyPatch,
                                   caplog: pytest.LogCaptureFixture) -> None:
    stale = types.ModuleType("emulator.flight._solo_native")
    stale.SOURCE_SHA256 = "0" * 64  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "emulator.flight._solo_native", stale)
    with caplog.at_level(logging.WARNING, logger="mavswarm.native"):
        assert native.compiled("solo") is None
    assert "solo.py changed since it was compiled" in caplog.text
    fresh = hashlib.sha256((ROOT / "emulator" / "flight" / "solo.py").read_bytes()).hexdigest()
    stale.SOURCE_SHA256 = fresh  # type: ignore[attr-defined]
    assert native.compiled("solo") is stale


def test_pure_python_can_be_asked_for(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MAVSWARM_PURE_PYTHON", "1")
    assert native.compiled("solo") is None and native.compiled("cruise") is None


@pytest.mark.parametrize("wind", [False, True])
def test_compiled_solo_steps_are_bit_identical(wind: bool) -> None:
    compiled = _built("solo")
    rng = np.random.default_rng(11 + wind)
    for _ in range(30):
        dyn = _random_dynamics(rng, 12, wind)
        pure = [solo.SoloVehicle(dyn, k, DT_S, None) for k in range(dyn.n)]
        fast = [compiled.SoloVehicle(dyn, k, DT_S, None) for k in range(dyn.n)]
        pure_bits, fast_bits = [0] * dyn.n, [0] * dyn.n
        for step in range(1, 60):
            t_s = step * DT_S
            assert (solo.step_all(pure, t_s, pure_bits)
                    == compiled.step_all(fast, t_s, fast_bits))
            assert pure_bits == fast_bits
        for a, b in zip(pure, fast, strict=True):
            assert ((a.px, a.py, a.pz, a.vx, a.vy, a.vz, a.ax, a.ay, a.az, a.yaw, a.yaw_step,
                     a.tracking, a.yaw_tracking, a.moving)
                    == (b.px, b.py, b.pz, b.vx, b.vy, b.vz, b.ax, b.ay, b.az, b.yaw, b.yaw_step,
                        b.tracking, b.yaw_tracking, b.moving))
            a_dyn, b_dyn = copy.deepcopy(dyn), copy.deepcopy(dyn)
            a.store(a_dyn)
            b.store(b_dyn)
            assert a_dyn.velocity_m_s.tobytes() == b_dyn.velocity_m_s.tobytes()


MISSIONS = """
import json, sys
sys.path.insert(0, {perf!r})
from stepped_speedup import fly_core
import emulator.flight.native as native
result = fly_core(6, 50.0)
print(json.dumps([sorted(native.COMPILED), result["digest"], result["steps"]]))
"""


@pytest.mark.slow
def test_a_fleet_flies_the_same_compiled_or_not() -> None:
    for name in build_native.NATIVE:
        _built(name)
    runs = []
    for pure in ("1", "0"):
        out = subprocess.run(
            [sys.executable, "-c", MISSIONS.format(perf=str(ROOT / "perf"))],
            env={**os.environ, "MAVSWARM_PURE_PYTHON": pure}, cwd=ROOT, capture_output=True,
            text=True, check=True, timeout=120)
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    (pure_modules, *pure_truth), (fast_modules, *fast_truth) = runs
    assert pure_modules == [] and fast_modules == sorted(build_native.NATIVE)
    assert pure_truth == fast_truth  # the whole ground truth's digest, and the steps


def test_the_modules_compiled_are_the_ones_swapped() -> None:
    assert set(build_native.NATIVE) == {"solo", "cruise", "solo_battery"}
    assert native.SoloVehicle in (solo.SoloVehicle, getattr(native.compiled("solo"),
                                                            "SoloVehicle", None))
    assert native.cruise_plan in (cruise.cruise_plan, getattr(native.compiled("cruise"),
                                                              "cruise_plan", None))


def test_degrees_by_the_constant_are_math_degrees_to_the_last_bit() -> None:
    """The compiled steps turn radians into degrees with DEG_PER_RAD instead of calling
    math.degrees: the same double for every angle atan2 returns, and for any other value."""
    assert 180.0 / math.pi == DEG_PER_RAD
    rng = np.random.default_rng(7)
    angles = np.arctan2(rng.uniform(-1e3, 1e3, 200_000), rng.uniform(-1e3, 1e3, 200_000))
    others = rng.uniform(-1e300, 1e300, 20_000)
    edges = [0.0, -0.0, math.pi, -math.pi, math.pi / 2, 5e-324, 1e308, math.inf, -math.inf]
    for x in [*angles.tolist(), *others.tolist(), *edges]:
        assert (x * DEG_PER_RAD).hex() == math.degrees(x).hex(), x


@pytest.mark.parametrize("module", ["pure", "compiled"])
def test_the_battery_deltas_in_floats_are_the_fleets_to_the_last_bit(module: str) -> None:
    from emulator.flight import solo_battery
    from emulator.flight.fleet import Fleet
    from emulator.scenario import default_scenario

    fleet_deltas = (solo_battery.fleet_deltas if module == "pure"
                    else _built("solo_battery").fleet_deltas)
    rng = np.random.default_rng(3)
    fleet = Fleet(default_scenario(12))
    for _ in range(50):
        fleet.dyn = _random_dynamics(rng, 12, wind=True)
        fleet.dyn.velocity_m_s[:3, 2] = (-0.0, 0.0, math.nan)  # maximum(vz, 0) keeps -0.0, NaN
        fleet.airborne[:] = rng.random(12) < 0.7
        fleet.armed[:] = rng.random(12) < 0.5
        fleet.bat.hover_endurance_s[:] = rng.uniform(60.0, 3600.0, 12)
        fleet.bat.charge_rate_pct_s[:] = np.where(rng.random(12) < 0.3, 0.5, 0.0)
        dt_s = float(rng.choice([0.02, 0.1, 0.5]))
        expected = fleet.bat.deltas(dt_s, fleet.airborne, fleet.armed, fleet.dyn.airspeed_m_s(),
                                    fleet.dyn.velocity_m_s[:, 2])
        got = np.array(fleet_deltas(fleet, dt_s))
        assert got.tobytes() == expected.tobytes()
