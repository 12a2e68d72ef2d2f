"""Vehicles stepped one by one (emulator.flight.solo) while the rest of the fleet cruises."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from emulator.flight.battery import FleetBattery
from emulator.flight.cruise import _cruise_steps_arrays, _cruise_steps_floats, cruise_plan
from emulator.flight.dynamics import (
    CONTROL_NONE,
    CONTROL_POSITION,
    TRACK_NONE,
    TRACK_PASS,
    TRACK_SETTLE,
    FleetDynamics,
)
from emulator.flight.fleet import Fleet, _SoloGuard
from emulator.flight.solo import (
    ARRIVED,
    OBSTACLE_STOP,
    STATE_FIELDS,
    TOUCHED_DOWN,
    YAW_REACHED,
    SoloVehicle,
    _surely_below,
)
from emulator.world import Obstacle
from tests.scenario_fixtures import tiny_scenario, vehicle

DT_S = 0.02


def _random_dynamics(rng: np.random.Generator, n: int, wind: bool) -> FleetDynamics:
    dyn = FleetDynamics(n)
    dyn.control[:] = rng.choice([CONTROL_NONE, CONTROL_POSITION, CONTROL_POSITION], n)
    dyn.position_m[:] = rng.uniform(-50.0, 50.0, (n, 3))
    dyn.position_m[:, 2] = rng.choice([0.01, 5.0, 30.0], n)
    dyn.goal_m[:] = dyn.position_m + rng.choice([0.0, 0.5, 3.0, 40.0], (n, 1)) * rng.normal(
        size=(n, 3))
    dyn.goal_m[rng.random(n) < 0.2, 2] = -1.0  # landing
    dyn.velocity_m_s[:] = rng.normal(0.0, 4.0, (n, 3)) * (rng.random((n, 1)) < 0.8)
    dyn.yaw_deg[:] = rng.uniform(0.0, 360.0, n)
    dyn.goal_yaw_deg[:] = np.where(rng.random(n) < 0.4, rng.uniform(0.0, 360.0, n), np.nan)
    dyn.yaw_tracking[:] = ~np.isnan(dyn.goal_yaw_deg) & (rng.random(n) < 0.5)
    dyn.tracking[:] = rng.choice([TRACK_NONE, TRACK_PASS, TRACK_SETTLE], n)
    dyn.speed_xy_m_s[:] = rng.uniform(2.0, 12.0, n)
    dyn.accel_xy_m_s2[:] = rng.uniform(1.0, 5.0, n)
    dyn.accel_z_m_s2[:] = rng.uniform(1.0, 5.0, n)
    dyn.airspeed_max_m_s[:] = rng.uniform(5.0, 15.0, n)
    dyn.acceptance_m[:] = rng.uniform(0.5, 5.0, n)
    dyn.wind_m_s = rng.normal(0.0, 6.0, 2) if wind else np.zeros(2)
    return dyn


@pytest.mark.parametrize("wind", [False, True])
def test_a_solo_step_moves_each_vehicle_as_the_fleet_step_moves_its_row(wind: bool) -> None:
    rng = np.random.default_rng(7 + wind)
    for _ in range(40):
        dyn = _random_dynamics(rng, 12, wind)
        solos = [SoloVehicle(dyn, k, DT_S, None) for k in range(dyn.n)]
        fleet_dyn = copy.deepcopy(dyn)
        events = fleet_dyn.step(DT_S)
        bits = [solo.step(DT_S) for solo in solos]
        for solo in solos:
            solo.store(dyn)
        dyn.position_m[:] = [(s.px, s.py, s.pz) for s in solos]
        np.testing.assert_allclose(dyn.position_m, fleet_dyn.position_m, rtol=0, atol=1e-9)
        np.testing.assert_allclose(dyn.velocity_m_s, fleet_dyn.velocity_m_s, rtol=0, atol=1e-9)
        np.testing.assert_allclose(dyn.accel_m_s2, fleet_dyn.accel_m_s2, rtol=0, atol=1e-6)
        yaw_gap = (dyn.yaw_deg - fleet_dyn.yaw_deg + 180.0) % 360.0 - 180.0
        assert np.abs(yaw_gap).max() < 1e-9
        assert (dyn.tracking == fleet_dyn.tracking).all()
        assert (dyn.yaw_tracking == fleet_dyn.yaw_tracking).all()
        for bit, expected in ((ARRIVED, events.arrived), (YAW_REACHED, events.yaw_reached),
                              (TOUCHED_DOWN, events.touched_down)):
            assert [k for k, b in enumerate(bits) if b & bit] == expected.tolist()


def _mission_fleet(n: int, obstacles: tuple[Obstacle, ...] = ()) -> Fleet:
    specs = [vehicle(k + 1, x=12.0 * k) for k in range(n)]
    return Fleet(tiny_scenario(specs, obstacles=obstacles))


def _fly_staggered(fleet: Fleet, fast_forward: bool) -> None:
    """Vehicle k takes off at k * 0.7 s and flies a dog-leg, so that some vehicles speed up
    or brake while others cruise."""
    for k, ap in enumerate(fleet.autopilots):
        while fleet.now_s < 0.7 * k:
            fleet.run(1, fast_forward=fast_forward)
        ap.arm()
        ap.takeoff(10.0 + k)
    while fleet.any_busy:
        fleet.run(50, fast_forward=fast_forward)
    for k, ap in enumerate(fleet.autopilots):
        ap.reposition((200.0 + 30.0 * k, 150.0 - 20.0 * k, 15.0))
        fleet.run(13 * k + 1, fast_forward=fast_forward)
    while fleet.any_busy:
        fleet.run(50, fast_forward=fast_forward)
    for ap in fleet.autopilots:
        ap.land()
    while fleet.any_busy:
        fleet.run(50, fast_forward=fast_forward)


def _truth(fleet: Fleet) -> tuple[list[np.ndarray], list[tuple[float, str, str]]]:
    rec = fleet.recorder
    events = [(e.t_s, e.vehicle_id, e.kind) for e in rec.events()]
    return [rec.trajectory(v) for v in rec.vehicle_ids], events


def test_cruising_with_solo_vehicles_records_what_plain_steps_record() -> None:
    wall = Obstacle.disc("o1", "tower", (120.0, 60.0), 8.0, height_m=0.0)
    results = []
    for fast in (False, True):
        fleet = _mission_fleet(4, obstacles=(wall,))
        _fly_staggered(fleet, fast)
        results.append((fleet.now_s, *_truth(fleet)))
    (t_plain, rows_plain, events_plain), (t_fast, rows_fast, events_fast) = results
    assert t_plain == t_fast
    assert events_plain == events_fast
    assert any(kind == "landed" for _, _, kind in events_fast)
    for plain, fast in zip(rows_plain, rows_fast, strict=True):
        assert plain.shape == fast.shape
        assert np.array_equal(plain[:, 0], fast[:, 0])
        assert np.abs(plain[:, 1:4] - fast[:, 1:4]).max() < 1e-6


def test_cruising_with_solo_vehicles_is_deterministic() -> None:
    runs = []
    for _ in range(2):
        fleet = _mission_fleet(5)
        _fly_staggered(fleet, True)
        rows, events = _truth(fleet)
        runs.append((b"".join(r.tobytes() for r in rows), events))
    assert runs[0] == runs[1]


def test_the_cruise_plan_in_floats_is_the_plan_in_arrays() -> None:
    fleet = _mission_fleet(6, obstacles=(Obstacle.disc("o1", "tower", (90.0, 90.0), 5.0,
                                                       height_m=0.0),))
    for k, ap in enumerate(fleet.autopilots):
        ap.arm()
        ap.takeoff(8.0 + k)
    compared = 0
    for step in range(4000):
        if step == 600:
            for k, ap in enumerate(fleet.autopilots):
                ap.reposition((150.0 - 25.0 * k, 120.0 + 10.0 * k, 12.0))
        fleet.step()
        if step % 7:
            continue
        floats = _cruise_steps_floats(fleet)
        assert floats is not None
        arrays = _cruise_steps_arrays(fleet).tolist()
        for a, b in zip(floats, arrays, strict=True):
            assert (a == -math.inf) == (b == -math.inf)
            if math.isfinite(a) or math.isfinite(b):
                assert a == pytest.approx(b, rel=1e-9, abs=1e-6)
        compared += 1
    assert compared > 500


def test_a_solo_vehicle_from_the_plans_state_is_the_one_read_from_the_arrays() -> None:
    rng = np.random.default_rng(11)
    fleet = _mission_fleet(12)
    for _ in range(20):
        fleet.dyn = _random_dynamics(rng, 12, wind=True)
        plan = cruise_plan(fleet, 50, max_solo=12)
        assert plan is not None and plan.states is not None
        for k, state in zip(plan.solo.tolist(), plan.states, strict=True):
            assert len(state) == len(STATE_FIELDS)
            given = SoloVehicle(fleet.dyn, k, DT_S, None, state=state)
            read = SoloVehicle(fleet.dyn, k, DT_S, None)
            assert [given.step(DT_S * (i + 1)) for i in range(30)] == [
                read.step(DT_S * (i + 1)) for i in range(30)]
            assert (given.px, given.py, given.pz, given.yaw, given.tracking) == (
                read.px, read.py, read.pz, read.yaw, read.tracking)


def test_a_solo_vehicle_stops_at_an_obstacle_like_the_fleet_step() -> None:
    wall = Obstacle.disc("o1", "tower", (30.0, 0.0), 5.0, height_m=0.0)
    fleet = _mission_fleet(1, obstacles=(wall,))
    dyn = fleet.dyn
    dyn.control[0] = CONTROL_POSITION
    dyn.position_m[0] = (20.0, 0.0, 10.0)
    dyn.goal_m[0] = (60.0, 0.0, 10.0)
    dyn.velocity_m_s[0] = (8.0, 0.0, 0.0)
    fleet.guard.forget(0)
    solo = SoloVehicle(dyn, 0, fleet.dt_s, _SoloGuard(fleet))
    stops = [solo.step(fleet.dt_s * (i + 1)) & OBSTACLE_STOP for i in range(200)]
    assert any(stops)
    assert solo.px < 25.0  # never inside the tower (radius 5 m around x = 30)


def test_battery_levels_crossed_while_solo_vehicles_are_stepped_act_as_in_plain_steps(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The cruise keeps the charges in floats: a level crossed during it must stop it at the
    same step, with the same failsafe, as plain steps."""
    crossings = []  # levels worked out by the battery during a cruise (FleetBattery.set_pct)
    set_pct = FleetBattery.set_pct
    monkeypatch.setattr(FleetBattery, "set_pct",
                        lambda bat, pct: crossings.append(set_pct(bat, pct)) or crossings[-1])
    results = []
    for fast in (False, True):
        fleet = _mission_fleet(4)
        fleet.bat.pct[:] = [8.2 + 0.3 * k for k in range(4)]  # critical (7 %) on the way
        for k, ap in enumerate(fleet.autopilots):
            while fleet.now_s < 0.7 * k:
                fleet.run(1, fast_forward=fast)
            ap.arm()
            ap.takeoff(10.0 + k)
        while fleet.any_busy:
            fleet.run(50, fast_forward=fast)
        for k, ap in enumerate(fleet.autopilots):
            ap.reposition((200.0 + 30.0 * k, 150.0 - 20.0 * k, 15.0))
            fleet.run(13 * k + 1, fast_forward=fast)
        while fleet.any_busy:  # until the battery failsafes' returns have landed
            fleet.run(50, fast_forward=fast)
        rows, events = _truth(fleet)
        results.append((fleet.now_s, rows, events, fleet.bat.pct.copy()))
    (t_plain, rows_plain, events_plain, pct_plain), (t_fast, rows_fast, events_fast,
                                                     pct_fast) = results
    assert t_plain == t_fast
    assert events_plain == events_fast
    assert sum(kind == "failsafe" for _, _, kind in events_fast) >= 4
    assert any(changed.size for changed in crossings)
    np.testing.assert_allclose(pct_fast, pct_plain, rtol=0, atol=1e-9)
    for plain, fast in zip(rows_plain, rows_fast, strict=True):
        assert plain.shape == fast.shape
        assert np.abs(plain[:, 1:4] - fast[:, 1:4]).max() < 1e-6
        assert np.abs(plain[:, 5] - fast[:, 5]).max() < 1e-9  # the charge, step by step


@settings(max_examples=3000, deadline=None)
@given(x=st.floats(-1e6, 1e6), y=st.floats(-1e6, 1e6),
       stretch=st.floats(1.0 - 1e-6, 1.0 + 1e-6))
def test_the_solo_steps_hypot_shortcut_never_decides_otherwise_than_hypot(
        x: float, y: float, stretch: float) -> None:
    # limits at and around the vector's own length, where a shortcut could go wrong
    for limit in (math.hypot(x, y) * stretch, math.nextafter(math.hypot(x, y), math.inf),
                  math.hypot(x, y), 1e-13, 0.0, math.nan):
        if x * x + y * y < _surely_below(limit):
            assert math.hypot(x, y) < limit
