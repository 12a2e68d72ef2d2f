"""Window clipping of the truth, operator resets, the live recorder, and evaluation speed."""

from __future__ import annotations

import time

import numpy as np
import pytest
import shapely

from benchmark.scoring.validators import evaluate, parse_tree
from benchmark.scoring.validators.geometry import (
    Footprint,
    heading_delta_deg,
    point_segment_distance,
)
from benchmark.scoring.validators.track import build_track
from emulator.scenario import Scenario
from emulator.truth import TruthLog, TruthRecorder
from emulator.world import Target
from tests.scenario_fixtures import tiny_scenario, vehicle
from tests.test_validators_fixtures import check, context, lawnmower, log, rows


def test_track_is_interpolated_at_both_window_ends() -> None:
    truth = log({"d1": np.array([[0, 0, 0, 0, 0, 100], [1, 10, 0, 0, 0, 90],
                                 [2, 20, 0, 0, 0, 80]], dtype=float)})
    track = build_track(truth, "d1", 0.5, 1.5)
    assert track.t_s.tolist() == [0.5, 1.0, 1.5]
    assert track.xyz_m[:, 0].tolist() == [5.0, 10.0, 15.0]
    assert track.battery_pct.tolist() == [95.0, 90.0, 85.0]
    assert track.joined.tolist() == [True, True]
    assert build_track(truth, "d1", -5.0, -1.0).empty


def test_a_sparse_history_is_interpolated_from_the_true_sample_times() -> None:
    truth = log({"d1": np.array([[0, 0, 0, 10, 0, 100], [100, 100, 0, 10, 0, 90]], float)})
    track = build_track(truth, "d1", 50.0, 60.0)
    assert track.t_s.tolist() == [50.0, 60.0]
    assert track.xyz_m[:, 0].tolist() == [50.0, 60.0]


def test_a_resting_vehicle_is_held_until_the_window_end() -> None:
    truth = log({"d1": np.array([[0, 0, 0, 0, 0, 100], [1, 10, 0, 0, 0, 90]], dtype=float)},
                end_t_s=3.0)
    track = build_track(truth, "d1", 0.0, 5.0)
    assert track.t_s.tolist() == [0.0, 1.0, 3.0]
    assert track.xyz_m[-1].tolist() == [10.0, 0.0, 0.0]


def _recorder_with_resets() -> TruthRecorder:
    """d1 rests at (0, 0) with 20 % battery; at t 5.3 an operator moves it to (100, 0) and sets
    the battery to 100 %. The recorder stores rows only at 1 s keyframes (nothing moves)."""
    recorder = TruthRecorder(["d1"])
    position, battery = np.zeros((1, 3)), np.array([20.0])
    for step in range(501):
        t = step * 0.02
        if step == 265:
            position[0] = (100.0, 0.0, 0.0)
            battery[0] = 100.0
            recorder.record_event(t, "d1", "operator_place", position_m=[100.0, 0.0, 0.0])
            recorder.record_event(t, "d1", "operator_battery", battery_pct=100.0)
        recorder.record_step(t, position, np.zeros(1), battery, np.zeros(1, dtype=bool))
    return recorder


def test_operator_resets_take_effect_between_keyframes_and_are_not_flown() -> None:
    recorder = _recorder_with_resets()
    assert recorder.trajectory("d1", 5.0, 5.9)[:, 1].tolist() == [0.0]  # no row after 5.3 yet
    scen = tiny_scenario([vehicle(1)])
    ctx = context(recorder, scen, 5.5, 5.9)
    assert check(ctx, "drone_position", drone_id="d1", x=100, y=0, tolerance=0).passed
    assert check(ctx, "drone_battery_level", drone_id="d1", min_level=99).passed
    whole = context(recorder, scen, 0.0, 10.0)
    assert check(whole, "drone_has_moved_distance", drone_id="d1", min_distance=1).value == 0.0
    assert not check(whole, "drone_has_visited_position", drone_id="d1", x=50, y=0).passed
    assert check(whole, "drone_on_ground", drone_id="d1").passed


def test_recorded_hover_between_keyframes() -> None:
    recorder = TruthRecorder(["d1"])
    for step in range(601):
        t = step * 0.02
        z = min(t, 5.0) * 2.0  # climbs at 2 m/s to 10 m by t 5, then holds
        moving = np.array([t <= 5.0])
        recorder.record_step(t, np.array([[0.0, 0.0, z]]), np.zeros(1), np.array([90.0]), moving)
    scen = tiny_scenario([vehicle(1)])
    ctx = context(recorder, scen, 0.0, 12.0)
    assert check(ctx, "drone_hovering", drone_id="d1").passed
    assert check(ctx, "drone_has_hovered", drone_id="d1", min_duration=6.9).passed
    assert not check(ctx, "drone_has_hovered", drone_id="d1", min_duration=7.1).passed
    climbing = context(recorder, scen, 0.0, 4.0)
    assert check(climbing, "drone_status", drone_id="d1", expected_status="taking_off").passed


def test_geometry_helpers() -> None:
    assert heading_delta_deg(350.0, 10.0) == pytest.approx(20.0)
    assert heading_delta_deg(-90.0, 270.0) == pytest.approx(0.0)
    a, b = np.array([[0.0, 0.0], [5.0, 5.0]]), np.array([[10.0, 0.0], [5.0, 5.0]])
    assert point_segment_distance(a, b, np.array([5.0, 3.0])).tolist() == [3.0, 2.0]
    square = Target.polygon("sq", "Square", [(0, 0), (10, 0), (10, 10), (0, 10)])
    shape = Footprint.of_target(square)
    crossing = shape.segment_distance(np.array([[-5.0, 5.0], [-5.0, 13.0], [3.0, 3.0]]),
                                      np.array([[15.0, 5.0], [15.0, 13.0], [4.0, 4.0]]))
    assert crossing.tolist() == pytest.approx([0.0, 3.0, 0.0])
    assert shape.distance_xy(13.0, 14.0) == pytest.approx(5.0)


def test_polygon_segment_distance_matches_shapely() -> None:
    u_shape = [(0, 0), (30, 0), (30, 30), (20, 30), (20, 10), (10, 10), (10, 30), (0, 30)]
    shape = Footprint.of_target(Target.polygon("u", "U", u_shape))
    rng = np.random.default_rng(3)
    a, b = rng.uniform(-20, 50, size=(2, 500, 2))
    b[:100] = a[:100]  # some zero-length segments
    b[100:200, 1] = a[100:200, 1]  # and some horizontal ones
    expected = shapely.distance(shapely.linestrings(np.stack((a, b), axis=1)),
                                shapely.Polygon(u_shape))
    assert shape.segment_distance(a, b) == pytest.approx(expected, abs=1e-9)


def _swarm_truth(n: int, minutes: float) -> tuple[TruthLog, Scenario]:
    """n drones flying tours for the given minutes at 50 Hz, one lawnmowing an area."""
    t_end = minutes * 60.0
    trajectories = {}
    rng = np.random.default_rng(7)
    for k in range(n):
        keys = [(0.0, 10.0 * k, 0.0, 0.0), (5.0, 10.0 * k, 0.0, 20.0)]
        if k == 0:
            keys += [(t + 5.0, x, y, z) for t, x, y, z in
                     lawnmower(0, 200, 200, 400, 20, z_m=20, speed_m_s=10)]
        while keys[-1][0] < t_end:
            x, y = rng.uniform(-500, 500, size=2)
            dist = np.hypot(x - keys[-1][1], y - keys[-1][2])
            keys.append((keys[-1][0] + dist / 10.0, x, y, 20.0))
        trajectories[f"d{k + 1}"] = rows(keys, t_end_s=t_end)[: int(t_end / 0.02) + 1]
    targets = [Target.disc(f"t{j}", f"T{j}", "fixed", (x, y, 0.0), 2.0)
               for j, (x, y) in enumerate(rng.uniform(-500, 500, size=(20, 2)))]
    targets.append(Target.polygon("area", "Area", [(0, 200), (200, 200), (200, 400), (0, 400)]))
    scen = tiny_scenario([vehicle(k + 1, 10.0 * k) for k in range(n)], targets=targets,
                    task_type="area_search")
    return log(trajectories, end_t_s=t_end), scen


TYPICAL_TREE = {"logic": "and", "checks": [
    {"endpoint": "drone_has_taken_off", "parameters": {"drone_id": "d1"}},
    {"endpoint": "drone_has_visited_position", "parameters": {"drone_id": "d2", "x": 10, "y": 0}},
    {"endpoint": "drone_has_visited_position", "parameters": {"drone_id": "d3", "x": 0, "y": 9}},
    {"endpoint": "drone_has_visited_position", "parameters": {"drone_id": "d4", "x": 5, "y": 5}},
    {"endpoint": "drone_has_moved_distance", "parameters": {"drone_id": "d5",
                                                            "min_distance": 100}},
    {"endpoint": "drone_has_moved_directed_distance", "parameters": {
        "drone_id": "d6", "min_distance": 10, "heading": 90, "tolerance": 5}},
    {"endpoint": "target_is_reached_by_drone", "parameters": {"drone_id": "d7",
                                                              "target_id": "t1"}},
    {"endpoint": "target_is_reached", "parameters": {"target_id": "t2"}},
    {"endpoint": "drone_hovering", "parameters": {"drone_id": "d8"}},
    {"endpoint": "drone_position", "parameters": {"drone_id": "d9", "x": 0, "y": 0, "z": 0}},
]}


def test_a_typical_tree_over_ten_drones_and_ten_minutes_is_fast() -> None:
    truth, scen = _swarm_truth(10, 10.0)
    tree = parse_tree(TYPICAL_TREE, scen)
    best = np.inf
    for _ in range(3):
        ctx = context(truth, scen, 0.0, 600.0)
        start = time.perf_counter()
        evaluation = evaluate(tree, ctx)
        best = min(best, time.perf_counter() - start)
    assert all(leaf.error is None for leaf in evaluation.leaves)
    assert best < 0.25, f"typical tree took {best * 1000:.1f} ms"
    heavy = parse_tree([{"endpoint": "task_progress", "parameters": {"expected_progress": 0}},
                        {"endpoint": "target_is_fully_searched",
                         "parameters": {"target_id": "area"}}], scen)
    start = time.perf_counter()
    evaluation = evaluate(heavy, context(truth, scen, 0.0, 600.0))
    assert time.perf_counter() - start < 2.0
    assert evaluation.leaves[1].value == pytest.approx(1.0, abs=0.01)
