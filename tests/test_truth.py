"""Behaviour of the ground-truth recorder and of logs loaded from its exports."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from emulator.truth import TruthEvent, TruthLog, TruthRecorder

DT_S = 0.02


def _ids(n: int) -> list[str]:
    return [f"uav{i}" for i in range(n)]


def _state(n: int, step: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Distinct, step-dependent values so every stored row can be traced to its step."""
    index = np.arange(n, dtype=np.float64)
    position_m = np.column_stack([index * 10.0 + step, index - step * 0.5, np.full(n, 2.0)])
    yaw_deg = (index * 7.0 + step) % 360.0
    battery_pct = 100.0 - step * 0.001 - index
    return position_m, yaw_deg, battery_pct


class NaiveTruth:
    """Reference: the storage rule written out per vehicle in plain Python."""

    def __init__(self, n: int, keyframe_s: float) -> None:
        self.rows: list[list[tuple[float, ...]]] = [[] for _ in range(n)]
        self.was_moving = [False] * n
        self.keyframe_s = keyframe_s
        self.first_t_s: float | None = None
        self.ticks = 0

    def step(
        self, t_s: float, pos: np.ndarray, yaw: np.ndarray, bat: np.ndarray, mv: list[bool]
    ) -> None:
        keyframe = self.first_t_s is None
        if keyframe:
            self.first_t_s = t_s
        assert self.first_t_s is not None
        if t_s >= self.first_t_s + (self.ticks + 1) * self.keyframe_s:
            keyframe = True
        while t_s >= self.first_t_s + (self.ticks + 1) * self.keyframe_s:
            self.ticks += 1
        for i, moving in enumerate(mv):
            if keyframe or moving or self.was_moving[i]:
                row = (t_s, *map(float, pos[i]), float(yaw[i]), float(bat[i]))
                self.rows[i].append(row)
        self.was_moving = list(mv)

    def window(self, i: int, t0_s: float | None, t1_s: float | None) -> np.ndarray:
        hi = math.inf if t1_s is None else t1_s
        if t0_s is None:
            out = [r for r in self.rows[i] if r[0] <= hi]
        else:
            before = [r for r in self.rows[i] if r[0] <= t0_s]
            start = [(t0_s, *before[-1][1:])] if before else []
            out = start + [r for r in self.rows[i] if t0_s < r[0] <= hi]
        return np.array(out, dtype=np.float64).reshape(-1, 6)


def test_idle_vehicles_store_only_keyframes() -> None:
    rec = TruthRecorder(_ids(3))
    idle = np.zeros(3, dtype=bool)
    for step in range(501):
        rec.record_step(step * DT_S, *_state(3, step), idle)
    for vehicle_id in rec.vehicle_ids:
        times = rec.trajectory(vehicle_id)[:, 0]
        np.testing.assert_allclose(times, np.arange(11.0), atol=1e-9)
    assert rec.stored_rows == 33
    assert rec.end_t_s == pytest.approx(10.0)


def test_keyframes_make_battery_drain_of_resting_vehicle_visible() -> None:
    rec = TruthRecorder(["a"], keyframe_s=0.5)
    for step in range(101):
        rec.record_step(step * DT_S, np.zeros((1, 3)), np.zeros(1), np.array([90.0 - step]), [0])
    battery = rec.trajectory("a")[:, 5]
    np.testing.assert_allclose(battery, 90.0 - np.arange(0, 101, 25))


def test_moving_vehicle_stores_one_row_per_step() -> None:
    rec = TruthRecorder(_ids(2))
    moving = np.array([True, False])
    for step in range(200):
        rec.record_step(step * DT_S, *_state(2, step), moving)
    rows = rec.trajectory("uav0")
    assert rows.shape == (200, 6)
    assert rows.dtype == np.float64
    np.testing.assert_allclose(rows[:, 0], np.arange(200) * DT_S)
    position_m, yaw_deg, battery_pct = _state(2, 123)
    np.testing.assert_array_equal(rows[123, 1:], [*position_m[0], yaw_deg[0], battery_pct[0]])
    assert rec.trajectory("uav1").shape[0] == 4  # keyframes at 0, 1, 2, 3 s


def test_stop_sample_is_stored_then_only_keyframes() -> None:
    rec = TruthRecorder(["a"])
    for step in range(40):
        rec.record_step(step * DT_S, *_state(1, step), [step < 10])
    times = rec.trajectory("a")[:, 0]
    np.testing.assert_allclose(times, np.arange(11) * DT_S)
    stop = rec.trajectory("a")[-1]
    position_m, _, _ = _state(1, 10)
    np.testing.assert_array_equal(stop[1:4], position_m[0])


def test_caller_may_reuse_its_arrays_in_place() -> None:
    rec = TruthRecorder(["a", "b"])
    position_m, yaw_deg, battery_pct = np.zeros((2, 3)), np.zeros(2), np.full(2, 50.0)
    moving = np.array([True, False])
    rec.record_step(0.0, position_m, yaw_deg, battery_pct, moving)
    position_m[:] = 99.0
    moving[:] = False
    rec.record_step(DT_S, position_m, yaw_deg, battery_pct, moving)
    rows = rec.trajectory("a")
    np.testing.assert_array_equal(rows[:, 1], [0.0, 99.0])
    assert rec.trajectory("b").shape[0] == 1


def test_window_includes_restamped_start_state() -> None:
    rec = TruthRecorder(["a"])
    for step in range(100):
        position_m = np.array([[min(step, 50), 0.0, 0.0]])
        rec.record_step(step * 0.1, position_m, [0.0], [80.0 - step * 0.1], [step < 50])
    window = rec.trajectory("a", 2.05, 3.01)
    assert window[0, 0] == 2.05
    assert window[0, 1] == 20.0
    np.testing.assert_allclose(window[1:, 1], np.arange(21, 31))
    on_sample = rec.trajectory("a", 2.0, 2.2)
    np.testing.assert_allclose(on_sample[:, 1], [20.0, 21.0, 22.0])
    resting = rec.trajectory("a", 7.25, 8.5)
    np.testing.assert_allclose(resting[:, 0], [7.25, 8.0])
    np.testing.assert_allclose(resting[:, 1], [50.0, 50.0])
    np.testing.assert_allclose(resting[:, 5], [73.0, 72.0])
    assert rec.trajectory("a", -5.0, 0.0).shape == (1, 6)
    assert rec.trajectory("a", t1_s=0.15).shape == (2, 6)
    with pytest.raises(ValueError, match="before"):
        rec.trajectory("a", 3.0, 2.0)


def test_position_at_interpolates_and_clamps() -> None:
    rec = TruthRecorder(["a"])
    rec.record_step(1.0, np.array([[0.0, 0.0, 0.0]]), [0.0], [100.0], [True])
    rec.record_step(2.0, np.array([[10.0, -4.0, 6.0]]), [0.0], [100.0], [True])
    rec.record_step(2.0, np.array([[11.0, -4.0, 6.0]]), [0.0], [100.0], [False])
    assert rec.position_at("a", 1.25) == pytest.approx((2.5, -1.0, 1.5))
    assert rec.position_at("a", 0.0) == (0.0, 0.0, 0.0)
    assert rec.position_at("a", 50.0) == (11.0, -4.0, 6.0)
    assert rec.position_at("a", 2.0) == (11.0, -4.0, 6.0)
    empty = TruthRecorder(["b"])
    with pytest.raises(ValueError, match="no samples"):
        empty.position_at("b", 0.0)


def test_events_filtered_by_vehicle_window_and_kind() -> None:
    rec = TruthRecorder(["a", "b"])
    rec.record_event(1.0, "a", "arm")
    rec.record_event(2.0, "b", "arm")
    landed = rec.record_event(3.0, "a", "landed", at=np.array([1.0, 2.0]), n=np.int64(3))
    rec.record_event(0.5, "b", "takeoff", altitude_m=10.0)
    assert [e.t_s for e in rec.events()] == [1.0, 2.0, 3.0, 0.5]
    assert [e.kind for e in rec.events("a")] == ["arm", "landed"]
    assert [e.t_s for e in rec.events(t0_s=1.0, t1_s=2.0)] == [1.0, 2.0]
    assert rec.events(kinds=["landed", "takeoff"]) == [landed, rec.events("b")[1]]
    assert rec.events("b", t0_s=0.0, t1_s=1.0, kinds="takeoff")[0].data == {"altitude_m": 10.0}
    assert landed.data == {"at": (1.0, 2.0), "n": 3}
    with pytest.raises(TypeError):
        landed.data["n"] = 4  # type: ignore[index]
    with pytest.raises(ValueError, match="JSON"):
        rec.record_event(4.0, "a", "photo", thing=object())
    with pytest.raises(KeyError, match="known vehicles: a, b"):
        rec.record_event(4.0, "zz", "arm")
    with pytest.raises(KeyError, match="zz"):
        rec.events("zz")


def test_time_must_be_non_decreasing_and_finite() -> None:
    rec = TruthRecorder(["a"])
    state = (np.zeros((1, 3)), np.zeros(1), np.ones(1), np.zeros(1, dtype=bool))
    rec.record_step(1.0, *state)
    rec.record_step(1.0, *state)
    for bad_t_s in (0.5, math.nan, math.inf):
        with pytest.raises(ValueError, match="non-decreasing"):
            rec.record_step(bad_t_s, *state)
    assert rec.end_t_s == 1.0


def test_shapes_and_ids_are_validated() -> None:
    rec = TruthRecorder(["a", "b"])
    with pytest.raises(ValueError, match="shapes"):
        rec.record_step(0.0, np.zeros((3, 3)), np.zeros(2), np.zeros(2), np.zeros(2, bool))
    with pytest.raises(KeyError, match="known vehicles: a, b"):
        rec.trajectory("c")
    with pytest.raises(ValueError, match="duplicate"):
        TruthRecorder(["a", "a"])
    with pytest.raises(ValueError, match="keyframe_s"):
        TruthRecorder(["a"], keyframe_s=0.0)
    assert math.isnan(rec.end_t_s)
    assert rec.trajectory("a").shape == (0, 6)


def test_export_load_round_trip(tmp_path: Path) -> None:
    rec = TruthRecorder(_ids(4), keyframe_s=0.5)
    rng = np.random.default_rng(7)
    for step in range(300):
        moving = rng.random(4) < 0.3
        rec.record_step(step * DT_S, *_state(4, step), moving)
        if step % 50 == 0:
            rec.record_event(step * DT_S, f"uav{step % 4}", "orbit", seq=step, tag=["x", 1])
    path = rec.export(tmp_path / "run.truth.npz")
    assert path == tmp_path / "run.truth.npz"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.truth.npz"]
    log = TruthRecorder.load(path)
    assert isinstance(log, TruthLog)
    assert log.vehicle_ids == rec.vehicle_ids
    assert log.end_t_s == rec.end_t_s
    assert log.keyframe_s == 0.5
    for vehicle_id in rec.vehicle_ids:
        np.testing.assert_array_equal(log.trajectory(vehicle_id), rec.trajectory(vehicle_id))
        np.testing.assert_array_equal(
            log.trajectory(vehicle_id, 1.01, 3.3), rec.trajectory(vehicle_id, 1.01, 3.3)
        )
        assert log.position_at(vehicle_id, 2.345) == rec.position_at(vehicle_id, 2.345)
    assert log.events() == rec.events()
    assert log.events("uav2", kinds=["orbit"]) == rec.events("uav2", kinds=["orbit"])
    assert rec.export(path) == path
    np.testing.assert_array_equal(TruthLog.load(path).trajectory("uav3"), log.trajectory("uav3"))


def test_load_rejects_other_files(tmp_path: Path) -> None:
    other = tmp_path / "other.npz"
    np.savez_compressed(other, x=np.zeros(3))
    with pytest.raises(ValueError, match="format"):
        TruthLog.load(other)


def test_snapshot_is_independent_of_later_steps() -> None:
    rec = TruthRecorder(["a"])
    rec.record_step(0.0, np.zeros((1, 3)), [0.0], [100.0], [True])
    snap = rec.snapshot()
    rec.record_step(0.02, np.ones((1, 3)), [0.0], [100.0], [True])
    assert snap.trajectory("a").shape == (1, 6)
    assert snap.end_t_s == 0.0
    assert rec.trajectory("a").shape == (2, 6)


def test_reads_between_steps_see_every_row_and_keep_what_they_returned() -> None:
    n = 3
    rec, ref = TruthRecorder(_ids(n)), NaiveTruth(n, 1.0)
    moving = np.array([True, False, True])
    earlier: list[tuple[np.ndarray, np.ndarray]] = []
    for step in range(3000):
        state = _state(n, step)
        rec.record_step(step * DT_S, *state, moving)
        ref.step(step * DT_S, *state, moving.tolist())
        if step % 37 == 0:
            got = rec.trajectory("uav0")
            np.testing.assert_array_equal(got, ref.window(0, None, None))
            earlier.append((got, got.copy()))
    for got, copy in earlier:  # later steps never change a trajectory already read
        np.testing.assert_array_equal(got, copy)
    for i, vehicle_id in enumerate(rec.vehicle_ids):
        np.testing.assert_array_equal(rec.trajectory(vehicle_id), ref.window(i, None, None))
    # the room kept for later rows stays within half the history (plus a first chunk)
    assert rec.nbytes < 1.6 * rec.stored_rows * 6 * 8 + 2**20


def test_event_equality_survives_json() -> None:
    event = TruthEvent(1.5, "a", "failsafe", {"fence": {"ids": [1, 2]}, "ok": True})
    assert TruthEvent(**event.to_json()) == event
    assert event.data["fence"]["ids"] == (1, 2)


@pytest.mark.slow
def test_memory_bounded_for_idle_swarm_over_an_hour() -> None:
    n, steps = 250, 180_000
    rec = TruthRecorder(_ids(n))
    position_m, yaw_deg = np.zeros((n, 3)), np.zeros(n)
    battery_pct, idle = np.full(n, 100.0), np.zeros(n, dtype=bool)
    for step in range(steps):
        rec.record_step(step * DT_S, position_m, yaw_deg, battery_pct, idle)
    rows_per_vehicle = math.floor((steps - 1) * DT_S) + 1
    assert rec.stored_rows == n * rows_per_vehicle
    assert rec.stored_rows < n * steps / 40
    assert rec.nbytes < 2 * n * rows_per_vehicle * 6 * 8 + 4 * 2**20


def test_many_moving_vehicles_match_reference_across_flushes() -> None:
    n, steps = 10, 1500
    rec, ref = TruthRecorder(_ids(n)), NaiveTruth(n, 1.0)
    rng = np.random.default_rng(3)
    for step in range(steps):
        moving = rng.random(n) < 0.8
        state = _state(n, step)
        rec.record_step(step * 0.125, *state, moving)
        ref.step(step * 0.125, *state, moving.tolist())
    for i, vehicle_id in enumerate(rec.vehicle_ids):
        np.testing.assert_array_equal(rec.trajectory(vehicle_id), ref.window(i, None, None))


def test_blocks_of_the_whole_fleet_and_partial_blocks_match_reference() -> None:
    # All-moving blocks are split by vehicle without sorting; a partial block (or a block
    # larger than the stage) takes the sorting path: every vehicle's rows come out the same.
    n = 7
    rec, ref = TruthRecorder(_ids(n)), NaiveTruth(n, 1.0)
    step, rng = 0, np.random.default_rng(5)
    for count, share in ((3, 1.0), (700, 1.0), (40, 0.5), (1, 1.0), (2000, 1.0), (9, 0.0),
                         (300, 1.0)):
        t_s = np.arange(step, step + count) * 0.02
        states = [_state(n, s) for s in range(step, step + count)]
        moving = rng.random(n) < share
        rec.record_steps(t_s, np.stack([s[0] for s in states]), states[0][1],
                         np.stack([s[2] for s in states]), moving)
        for i, t in enumerate(t_s.tolist()):
            ref.step(t, states[i][0], states[0][1], states[i][2], moving.tolist())
        step += count
        if step % 2:
            np.testing.assert_array_equal(rec.trajectory("uav1"), ref.window(1, None, None))
    for i, vehicle_id in enumerate(rec.vehicle_ids):
        np.testing.assert_array_equal(rec.trajectory(vehicle_id), ref.window(i, None, None))


@st.composite
def _recordings(draw: st.DrawFn) -> tuple[int, float, list[tuple[float, list[bool], bool]]]:
    n = draw(st.integers(1, 4))
    keyframe_s = draw(st.sampled_from([0.5, 1.0, 2.0]))
    dts = draw(st.lists(st.sampled_from([0.0, 0.125, 0.25, 0.5, 1.5]), min_size=1, max_size=60))
    steps = []
    t_s = draw(st.sampled_from([0.0, 3.25, 100.0]))
    for dt_s in dts:
        t_s += dt_s
        mask = draw(st.lists(st.booleans(), min_size=n, max_size=n))
        steps.append((t_s, mask, draw(st.booleans())))
    return n, keyframe_s, steps


@settings(max_examples=150, deadline=None)
@given(recording=_recordings(), data=st.data())
@pytest.mark.slow
def test_trajectory_matches_naive_reference(
    recording: tuple[int, float, list[tuple[float, list[bool], bool]]], data: st.DataObject
) -> None:
    n, keyframe_s, steps = recording
    rec, ref = TruthRecorder(_ids(n), keyframe_s=keyframe_s), NaiveTruth(n, keyframe_s)
    for step, (t_s, mask, query_now) in enumerate(steps):
        state = _state(n, step)
        rec.record_step(t_s, *state, np.array(mask))
        ref.step(t_s, *state, mask)
        if query_now:
            np.testing.assert_array_equal(rec.trajectory("uav0"), ref.window(0, None, None))
    times = [t for t, _, _ in steps]
    bound = st.one_of(st.none(), st.sampled_from(times), st.floats(times[0] - 1, times[-1] + 1))
    for i, vehicle_id in enumerate(rec.vehicle_ids):
        np.testing.assert_array_equal(rec.trajectory(vehicle_id), ref.window(i, None, None))
        t0_s, t1_s = data.draw(bound), data.draw(bound)
        if t0_s is not None and t1_s is not None and t1_s < t0_s:
            t0_s, t1_s = t1_s, t0_s
        expected = ref.window(i, t0_s, t1_s)
        np.testing.assert_array_equal(rec.trajectory(vehicle_id, t0_s, t1_s), expected)


def test_event_data_of_plain_scalars_reads_as_after_a_json_round_trip():
    data = {"alt_m": 12.5, "n": 3, "ok": False, "why": None, "nan": math.nan, "inf": -math.inf,
            "np": np.float64(0.1), "nested": {"ids": (1, 2)}}
    event = TruthEvent(2.0, "a", "failsafe", data)
    assert type(event.data["np"]) is float and event.data["nested"]["ids"] == (1, 2)
    assert math.isnan(event.data["nan"]) and event.data["inf"] == -math.inf
    flat = TruthEvent(2.0, "a", "failsafe", {"alt_m": 12.5, "ok": True, "why": None})
    assert flat.to_json()["data"] == {"alt_m": 12.5, "ok": True, "why": None}
    with pytest.raises(TypeError):
        flat.data["alt_m"] = 1.0  # read-only either way
    with pytest.raises(ValueError, match="not JSON-serialisable"):
        TruthEvent(2.0, "a", "failsafe", {"when": object()})
