"""Moving targets: the reference's kinematics in simulated time, recorded, sensed and judged
where they truly are."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from emulator.flight.fleet import Fleet
from emulator.scenario import load_scenario
from emulator.target_motion import MovingTargets, TargetLegs, motion_spec, obstacle_entry
from emulator.truth import TruthLog
from emulator.world import Obstacle, Target
from tests.scenario_fixtures import tiny_scenario, vehicle
from tests.test_validators_fixtures import check, context, log, rows

EXAMPLE = Path(__file__).parent / "reference" / "Example_Session_Target_Tracking.json"


def test_mode_follows_the_reference_priority() -> None:
    assert motion_spec((0, 0, 0), (1, 0, 0), [(0, 0, 0), (5, 0, 0)], 10).mode == "velocity"
    assert motion_spec((0, 0, 0), (0, 0, 0), [(0, 0, 0), (5, 0, 0)], 10).mode == "path"
    assert motion_spec((0, 0, 0), (1, 0, 0), None, 0).mode == "stationary"
    assert motion_spec((0, 0, 0), None, [(1, 1, 0), (1, 1, 0)], 10).mode == "stationary"
    path = motion_spec((0, 0, 0), None, [(0, 0, 0), (30, 40, 0)], 10)
    assert path.speed_m_s == pytest.approx(5.0)


def test_velocity_mode_ping_pongs_after_its_duration() -> None:
    legs = TargetLegs(motion_spec((10, 0, 0), (2, 1, 0), None, 5.0))
    xyz = legs.positions(np.array([0.0, 2.5, 5.0, 7.5, 10.0, 12.5, 20.0]))
    assert xyz[:, :2] == pytest.approx(np.array(
        [[10, 0], [15, 2.5], [20, 5], [15, 2.5], [10, 0], [15, 2.5], [10, 0]]))


def test_path_mode_runs_at_length_over_duration_and_bounces_at_the_ends() -> None:
    path = [(0, 0, 0), (30, 0, 0), (30, 40, 0)]  # 70 m in 14 s: 5 m/s
    legs = TargetLegs(motion_spec((0, 0, 0), None, path, 14.0))
    xyz = legs.positions(np.array([0.0, 3.0, 6.0, 14.0, 20.0, 28.0]))
    assert xyz[:, :2] == pytest.approx(np.array(
        [[0, 0], [15, 0], [30, 0], [30, 40], [30, 10], [0, 0]]))


def test_a_target_turns_round_where_it_meets_an_obstacle() -> None:
    wall = Obstacle.polygon("o1", "Wall", [(50, -10), (60, -10), (60, 10), (50, 10)])
    legs = TargetLegs(motion_spec((0, 0, 0), (5, 0, 0), None, 20.0), obstacle_entry([wall]))
    xyz = legs.positions(np.array([5.0, 10.0, 15.0, 30.0]))
    assert xyz[:, 0].tolist() == pytest.approx([25, 50, 25, -50], abs=1e-5)
    # A building below the target's altitude does not stop it.
    low = Obstacle.polygon("o2", "Low", [(50, -10), (60, -10), (60, 10), (50, 10)], height_m=5)
    high = TargetLegs(motion_spec((0, 0, 8), (5, 0, 0), None, 20.0), obstacle_entry([low]))
    assert high.positions(np.array([15.0]))[0, 0] == pytest.approx(75.0)


def test_rows_are_exact_breakpoints_for_linear_interpolation() -> None:
    moving = MovingTargets(["m"], [motion_spec((0, 0, 0), (1, 0, 0), None, 4.0)])
    table = moving.rows("m", 1.0, 11.0)
    assert table[:, 0].tolist() == pytest.approx([1, 4, 8, 11])
    times = np.linspace(1.0, 11.0, 41)
    interp = np.interp(times, table[:, 0], table[:, 1])
    assert interp == pytest.approx(moving.legs("m").positions(times)[:, 0])


def _fleet_with_mover() -> Fleet:
    mover = Target.disc("m", "Mover", "moving", (100.0, 0.0, 0.0), 2.0,
                        motion=motion_spec((100, 0, 0), (0, 4, 0), None, 10.0))
    scenario = tiny_scenario([vehicle(1, 100.0, 60.0)], targets=[mover])
    return Fleet(scenario)


def test_the_physics_step_moves_targets_into_truth_and_perception(tmp_path: Path) -> None:
    fleet = _fleet_with_mover()
    sensed = fleet.sensor.sense((100.0, 60.0, 0.0), 30.0).targets
    assert sensed == ()  # 60 m away at t = 0
    for _ in range(round(8.0 / fleet.dt_s)):
        fleet.step()
    assert fleet.targets is not None
    assert fleet.targets.current()["m"] == pytest.approx((100.0, 32.0, 0.0))
    seen = fleet.sensor.sense((100.0, 60.0, 0.0), 30.0).targets
    assert [(s.id, s.position_m[1]) for s in seen] == [("m", pytest.approx(32.0))]
    fleet.run(500)  # idle: nothing busy, one step
    truth = fleet.recorder.target_trajectory("m")
    assert truth[0].tolist() == [0.0, 100.0, 0.0, 0.0]
    assert truth[-1, 0] == pytest.approx(fleet.now_s)
    loaded = TruthLog.load(fleet.recorder.export(tmp_path / "truth.npz"))
    assert loaded.target_trajectory("m", 2.0, 6.0) == pytest.approx(
        np.array([[2.0, 100.0, 8.0, 0.0], [6.0, 100.0, 24.0, 0.0]]))


def test_same_start_same_truth() -> None:
    a, b = Fleet(load_scenario(EXAMPLE)), Fleet(load_scenario(EXAMPLE))
    for fleet in (a, b):
        for _ in range(1500):
            fleet.step()
    assert a.targets is not None and b.targets is not None
    for target in a.targets.ids:
        assert np.array_equal(a.recorder.target_trajectory(target),
                              b.recorder.target_trajectory(target))


def _chase_context() -> tuple[object, object]:
    mover = Target.disc("m", "Mover", "moving", (0.0, 0.0, 0.0), 1.0)
    scenario = tiny_scenario([vehicle(1), vehicle(2)], targets=[mover])
    # The target runs east at 5 m/s for 60 s. d1 hovers at x = 100 (meets it around t 20);
    # d2 flies with it 30 m north of it from t 10 to t 40 (always 30 m away: out of range).
    target = np.array([[0.0, 0.0, 0.0, 0.0], [60.0, 300.0, 0.0, 0.0]])
    d1 = rows([(0, 100, 0, 10), (60, 100, 0, 10)], dt_s=1.0)
    d2 = rows([(0, 50, 30, 10), (10, 50, 30, 10), (40, 200, 30, 10), (60, 200, 30, 10)],
              dt_s=1.0)
    truth = log({"d1": d1, "d2": d2}, end_t_s=60.0)
    truth = TruthLog(truth.vehicle_ids, [truth.trajectory(v) for v in truth.vehicle_ids],
                     end_t_s=60.0, target_trajectories={"m": target})
    return truth, scenario


def test_reach_is_judged_against_where_the_target_was() -> None:
    truth, scenario = _chase_context()
    ctx = context(truth, scenario, 0.0, 60.0)  # type: ignore[arg-type]
    # d1 is in range (20 m + 1 m) while |5 t - 100| <= 21: t in [15.8, 24.2], so its 1 s
    # hover segments from 15 to 25 are in range; the tracking window adds 10 s.
    leaf = check(ctx, "moving_target_tracked", target_id="m", drone_id="d1")
    assert leaf.value == pytest.approx(10.0 + 10.0, abs=1e-6)
    assert not check(ctx, "target_is_reached_by_drone", target_id="m", drone_id="d2").passed
    assert check(ctx, "target_is_reached_by_drone", target_id="m", drone_id="d1").passed
    assert check(ctx, "moving_target_reached_in_zone", target_id="m", drone_id="d1",
                 x=90.0, y=0.0, radius=5.0).passed
    assert not check(ctx, "moving_target_reached_in_zone", target_id="m", drone_id="d1",
                     x=200.0, y=0.0, radius=20.0).passed
    # Current-state checks look at the target at the end of the window (x = 300).
    late = context(truth, scenario, 0.0, 60.0)  # type: ignore[arg-type]
    leaf = check(late, "target_within_drone_distance", target_id="m", drone_id="d2",
                 max_distance=150.0)
    assert leaf.value == pytest.approx(math.hypot(100.0, 30.0) - 1.0)


def test_a_drone_flying_with_the_target_keeps_it_tracked() -> None:
    mover = Target.disc("m", "Mover", "moving", (0.0, 0.0, 0.0), 1.0)
    scenario = tiny_scenario([vehicle(1)], targets=[mover])
    target = np.array([[0.0, 0.0, 0.0, 0.0], [60.0, 300.0, 0.0, 0.0]])
    d1 = rows([(0, 0, 10, 10), (40, 200, 10, 10), (41, 200, 10, 10), (60, 200, 10, 10)])
    base = log({"d1": d1}, end_t_s=60.0)
    truth = TruthLog(("d1",), [base.trajectory("d1")], end_t_s=60.0,
                     target_trajectories={"m": target})
    ctx = context(truth, scenario, 0.0, 60.0)
    # With the target (10 m off) until t 40, then it pulls away: out of range once
    # 5 t - 200 > sqrt(21^2 - 10^2), at t 43.69.
    leaf = check(ctx, "moving_target_tracked", target_id="m", drone_id="d1", min_duration=50)
    assert leaf.passed and leaf.value == pytest.approx(43.69 + 10.0, abs=0.05)


def test_target_tracking_progress_counts_what_is_tracked_at_the_end() -> None:
    truth, scenario = _chase_context()
    tracking = dataclasses.replace(scenario, task_type="target_tracking")  # type: ignore[type-var]
    # d1 had the target in range until t 25: tracked until t 35, stale afterwards.
    assert check(context(truth, tracking, 0.0, 30.0), "task_progress",  # type: ignore[arg-type]
                 expected_progress=1.0).passed
    late = context(truth, tracking, 0.0, 40.0)  # type: ignore[arg-type]
    leaf = check(late, "task_progress", expected_progress=0.5)
    assert (leaf.result, leaf.value) == (False, 0.0)
    assert check(late, "task_done").passed  # every target was reached at some time


def test_multiuav_plat_target_records_give_a_moving_target_where_it_is_now() -> None:
    from types import SimpleNamespace

    from benchmark.server.compat.entities import entity_records
    fleet = _fleet_with_mover()
    for _ in range(100):  # 2 s at 4 m/s
        fleet.step()
    data = {"targets": [{"id": "m", "name": "Mover", "type": "moving",
                         "position": {"x": 100.0, "y": 0.0, "z": 0.0},
                         "velocity": {"x": 0.0, "y": 4.0, "z": 0.0}}]}
    live = SimpleNamespace(
        session=SimpleNamespace(data=data, scenario=fleet.scenario),
        swarm=SimpleNamespace(fleet=fleet, recorder=fleet.recorder), task_start_s=0.0,
        services=SimpleNamespace(clock_s=lambda: fleet.now_s))
    record = entity_records(live, "targets")["m"]  # type: ignore[arg-type]
    assert record["position"] == {"x": 100.0, "y": 8.0, "z": 0.0}
    assert record["velocity"] == {"x": 0.0, "y": 4.0, "z": 0.0}
    assert record["tracking_status"] == "never_tracked"  # the drone stayed 52 m away
    assert data["targets"][0]["position"]["y"] == 0.0  # the session file is left alone


def _entry_against_every_obstacle(obstacles: list[Obstacle], a: np.ndarray, b: np.ndarray
                                  ) -> float | None:
    """Reference: every obstacle tested, the earliest entry kept."""
    import shapely
    if np.allclose(a[:2], b[:2]):
        return None
    line = shapely.LineString([a[:2], b[:2]])
    best = None
    for o in obstacles:
        if not o.blocks_altitude(float(max(a[2], b[2]))):
            continue
        if shapely.intersects_xy(o.footprint, float(a[0]), float(a[1])):
            continue
        if not line.intersects(o.footprint):
            continue
        coords = shapely.get_coordinates(line.intersection(o.footprint))
        f = min(line.project(shapely.Point(c)) for c in coords) / line.length
        best = f if best is None or f < best else best
    return best


def test_entry_tests_only_obstacles_near_the_move_and_finds_the_same() -> None:
    rng = np.random.default_rng(11)
    obstacles = [Obstacle.disc(f"d{i}", "disc", tuple(rng.uniform(-300, 300, 2).tolist()),
                               float(rng.uniform(3, 25)), height_m=float(rng.choice([0, 10, 40])))
                 for i in range(40)]
    obstacles.append(Obstacle.polygon("w", "Wall", [(0, -50), (4, -50), (4, 50), (0, 50)]))
    entry = obstacle_entry(obstacles)
    hits = 0
    for _ in range(600):
        a = np.array([*rng.uniform(-320, 320, 2), rng.uniform(0, 50)])
        b = a + np.array([*rng.uniform(-150, 150, 2), 0.0])
        want = _entry_against_every_obstacle(obstacles, a, b)
        assert entry(a, b) == want
        hits += want is not None
    assert 50 < hits < 550  # both kinds of moves were tried
