"""History checks: events and flown trajectory inside the window."""

from __future__ import annotations

import numpy as np
import pytest

from emulator.world import Target
from tests.scenario_fixtures import tiny_scenario, vehicle
from tests.test_validators_fixtures import check, context, event, log, rows

DRONES = [vehicle(1), vehicle(2, 50.0), vehicle(3, 0.0, 50.0), vehicle(4, 0.0, -50.0)]
SCENARIO = tiny_scenario(DRONES, targets=[Target.disc("t1", "Crate", "fixed", (100, 0, 0), 2.0),
                                     Target.disc("t2", "Box", "fixed", (0, 300, 0), 2.0)])

# d1: climbs over (0, 0) to 20 m (t 2-6), east to (100, 0) (t 6-16), hovers (t 16-30),
# north to (100, 100) (t 30-40), descends (t 40-50), rests until 60.
D1 = rows([(0, 0, 0, 0), (2, 0, 0, 0), (6, 0, 0, 20), (16, 100, 0, 20), (30, 100, 0, 20),
           (40, 100, 100, 20), (50, 100, 100, 0)], t_end_s=60.0)
# d2: climbs over (50, 0) to 10 m (t 2-5) and hovers.
D2 = rows([(0, 50, 0, 0), (2, 50, 0, 0), (5, 50, 0, 10)], t_end_s=60.0)
# d3: on the ground on a charger; battery 50 % until t 10, charges to 100 % by t 20, flies a
# little from t 35 after an operator set the battery to 60 % at t 25 and a charge from t 30.
D3 = rows([(0, 0, 50, 0), (35, 0, 50, 0), (40, 0, 50, 5)], t_end_s=60.0)
D3[:, 5] = np.interp(D3[:, 0], [0, 10, 20, 25, 30, 35, 60], [50, 50, 100, 100, 60, 70, 60])
D3[(D3[:, 0] > 25) & (D3[:, 0] <= 30), 5] = 60.0
# d4: on the ground at (0, -50), placed by an operator at (500, -50) at t 10.
D4 = rows([(0, 0, -50, 0)], t_end_s=60.0)
D4[D4[:, 0] > 10.0, 1] = 500.0

EVENTS = [
    event(1.0, "d1", "arm"), event(2.0, "d1", "takeoff", altitude_m=20.0),
    event(6.0, "d1", "takeoff_complete", position_m=[0.0, 0.0, 20.0]),
    event(12.0, "d1", "message_sent", to="d2", text="hello d2"),
    event(13.0, "d1", "message_broadcast", text="all: go", recipients=["d2", "d3", "d4"]),
    event(14.0, "d1", "message_sent", to="d3", text="status"),
    event(20.0, "d1", "photo", index=1, position_m=[100.0, 0.0, 20.0], targets=["t1"],
          obstacles=[], vehicles=[]),
    event(35.0, "d1", "photo", index=2, position_m=[100.0, 50.0, 20.0], targets=[],
          obstacles=[], vehicles=[]),
    event(50.0, "d1", "landed", position_m=[100.0, 100.0, 0.0]),
    event(5.0, "d2", "takeoff_complete", position_m=[50.0, 0.0, 10.0]),
    event(10.0, "d3", "charging", battery_pct=50.0),
    event(20.0, "d3", "charged", battery_pct=100.0),
    event(25.0, "d3", "operator_battery", battery_pct=60.0),
    event(30.0, "d3", "charging", battery_pct=60.0),
    event(35.0, "d3", "arm"),
    event(10.0, "d4", "operator_place", position_m=[500.0, -50.0, 0.0]),
]
TRUTH = log({"d1": D1, "d2": D2, "d3": D3, "d4": D4}, EVENTS, end_t_s=60.0)
ALL = context(TRUTH, SCENARIO, 0.0, 60.0)


def test_drone_has_taken_off_altitude_band() -> None:
    assert check(ALL, "drone_has_taken_off", drone_id="d1").value == 1
    assert not check(ALL, "drone_has_taken_off", drone_id="d1", min_altitude=25).passed
    assert check(ALL, "drone_has_taken_off", drone_id="d1", min_altitude=20,
                 max_altitude=20).passed
    assert check(ALL, "drone_has_taken_off", drone_id="d1", min_altitude=21, max_altitude=22,
                 tolerance=1).passed
    assert not check(ALL, "drone_has_taken_off", drone_id="d1", min_altitude=22,
                     max_altitude=25, tolerance=1).passed
    assert not check(ALL, "drone_has_taken_off", drone_id="d3").passed


def test_drone_has_landed_counts_landed_events_in_the_window() -> None:
    assert check(ALL, "drone_has_landed", drone_id="d1").passed
    assert not check(ALL, "drone_has_landed", drone_id="d1", min_count=2).passed
    later = context(TRUTH, SCENARIO, 51.0, 60.0)
    leaf = check(later, "drone_has_landed", drone_id="d1")
    assert (leaf.result, leaf.value) == (False, 0)
    # The reference template complete_flight_cycle passes max_altitude here; it is ignored.
    assert check(ALL, "drone_has_landed", drone_id="d1", max_altitude=1.0).passed


def test_visited_position_uses_the_flown_segments_between_samples() -> None:
    leaf = check(ALL, "drone_has_visited_position", drone_id="d1", x=50.1, y=0, tolerance=0.01)
    assert (leaf.result, leaf.value) == (True, 0.0)
    sparse = log({"d1": np.array([[0, 0, 0, 10, 0, 100], [10, 100, 0, 10, 0, 99]], float)})
    ctx = context(sparse, tiny_scenario([vehicle(1)]), 0.0, 10.0)
    assert check(ctx, "drone_has_visited_position", drone_id="d1", x=50, y=0).passed
    leaf = check(ctx, "drone_has_visited_position", drone_id="d1", x=50, y=6, tolerance=5)
    assert (leaf.result, leaf.value) == (False, 6.0)
    assert check(ctx, "drone_has_visited_position", drone_id="d1", x=50, y=0, z=10).passed
    leaf = check(ctx, "drone_has_visited_position", drone_id="d1", x=50, y=0, z=0)
    assert (leaf.result, leaf.value) == (False, 10.0)


def test_visited_position_only_sees_the_window() -> None:
    ctx = context(TRUTH, SCENARIO, 30.0, 60.0)
    assert not check(ctx, "drone_has_visited_position", drone_id="d1", x=50, y=0).passed
    assert check(ctx, "drone_has_visited_position", drone_id="d1", x=100, y=60).passed


def test_moved_distance_is_horizontal_path_length() -> None:
    leaf = check(ALL, "drone_has_moved_distance", drone_id="d1", min_distance=199)
    assert (leaf.result, leaf.value) == (True, 200.0)
    assert not check(ALL, "drone_has_moved_distance", drone_id="d1", min_distance=201).passed


def test_an_operator_placement_is_not_flown_distance() -> None:
    leaf = check(ALL, "drone_has_moved_distance", drone_id="d4", min_distance=1)
    assert (leaf.result, leaf.value) == (False, 0.0)
    assert not check(ALL, "drone_has_visited_position", drone_id="d4", x=250, y=-50).passed
    assert check(ALL, "drone_position", drone_id="d4", x=500, y=-50).passed


def test_directed_distance_by_bearing() -> None:
    east = check(ALL, "drone_has_moved_directed_distance", drone_id="d1", min_distance=99,
                 heading=90)
    assert (east.result, east.value) == (True, 100.0)
    north = check(ALL, "drone_has_moved_directed_distance", drone_id="d1", min_distance=99,
                  heading=360, tolerance=1)
    assert (north.result, north.value) == (True, 100.0)
    leaf = check(ALL, "drone_has_moved_directed_distance", drone_id="d1", min_distance=1,
                 heading=45)
    assert (leaf.result, leaf.value) == (False, 0.0)


def test_drone_has_hovered_periods() -> None:
    assert check(ALL, "drone_has_hovered", drone_id="d1", min_duration=13.9).value == 1
    assert not check(ALL, "drone_has_hovered", drone_id="d1", min_duration=14.5).passed
    assert check(ALL, "drone_has_hovered", drone_id="d1").passed
    assert not check(ALL, "drone_has_hovered", drone_id="d1", min_count=2).passed
    assert not check(ALL, "drone_has_hovered", drone_id="d4").passed  # on the ground


def test_drone_has_taken_photo_count_and_position() -> None:
    assert check(ALL, "drone_has_taken_photo", drone_id="d1", min_count=2).passed
    assert not check(ALL, "drone_has_taken_photo", drone_id="d1", min_count=3).passed
    leaf = check(ALL, "drone_has_taken_photo", drone_id="d1", at_position={"x": 100, "y": 0})
    assert (leaf.result, leaf.value) == (True, 1)
    leaf = check(ALL, "drone_has_taken_photo", drone_id="d1",
                 at_position='{"x": 100, "y": 50, "z": 20}', tolerance=1)
    assert (leaf.result, leaf.value) == (True, 1)
    assert not check(ALL, "drone_has_taken_photo", drone_id="d1",
                     at_position={"x": 100, "y": 50, "z": 0}, tolerance=5).passed
    assert not check(ALL, "drone_has_taken_photo", drone_id="d1",
                     at_position={"x": 0, "y": 0}).passed


def test_target_in_photo_taken_by_drone() -> None:
    leaf = check(ALL, "target_in_photo_taken_by_drone", drone_id="d1", target_id="t1")
    assert (leaf.result, leaf.value) == (True, 1)
    assert not check(ALL, "target_in_photo_taken_by_drone", drone_id="d1", target_id="t2").passed


def test_drone_has_charged_amounts_and_full_charges() -> None:
    leaf = check(ALL, "drone_has_charged", drone_id="d3")
    assert (leaf.result, leaf.value) == (True, 2)
    assert check(ALL, "drone_has_charged", drone_id="d3", min_charge_amount=20).value == 1
    assert check(ALL, "drone_has_charged", drone_id="d3", min_charge_amount=60).value == 1
    late = context(TRUTH, SCENARIO, 26.0, 60.0)
    leaf = check(late, "drone_has_charged", drone_id="d3", min_charge_amount=20)
    assert (leaf.result, leaf.value) == (False, 0)
    assert check(late, "drone_has_charged", drone_id="d3", min_charge_amount=9.9).passed
    ongoing = context(TRUTH, SCENARIO, 0.0, 15.0)
    assert check(ongoing, "drone_has_charged", drone_id="d3", min_charge_amount=24.9).passed
    assert not check(ongoing, "drone_has_charged", drone_id="d3", min_charge_amount=25.1).passed
    assert not check(ALL, "drone_has_charged", drone_id="d1").passed


def test_drone_has_sent_message_with_recipient_and_content() -> None:
    assert check(ALL, "drone_has_sent_message", drone_id="d1", min_count=3).passed
    leaf = check(ALL, "drone_has_sent_message", drone_id="d1", to_drone_id="d2", min_count=3)
    assert (leaf.result, leaf.value) == (False, 2)
    assert not check(ALL, "drone_has_sent_message", drone_id="d2").passed
    leaf = check(ALL, "drone_has_sent_message_content", drone_id="d1", content="go")
    assert (leaf.result, leaf.value) == (True, 1)
    assert not check(ALL, "drone_has_sent_message_content", drone_id="d1", content="Go").passed
    assert not check(ALL, "drone_has_sent_message_content", drone_id="d1", content="status",
                     to_drone_id="d2").passed
    assert check(ALL, "drone_has_sent_message_content", drone_id="d1", content="status",
                 to_drone_id="d3").passed
    early = context(TRUTH, SCENARIO, 13.5, 60.0)
    assert check(early, "drone_has_sent_message", drone_id="d1").value == 1


def test_all_drones_have_taken_off() -> None:
    both = context(TRUTH, tiny_scenario(DRONES[:2]), 0.0, 60.0)
    leaf = check(both, "all_drones_have_taken_off")
    assert (leaf.result, leaf.value) == (True, 2)
    assert check(both, "all_drones_have_taken_off", min_altitude=15).value == 1
    assert not check(both, "all_drones_have_taken_off", min_altitude=15).passed
    now = context(TRUTH, tiny_scenario(DRONES[:2]), 0.0, 20.0)
    assert check(now, "all_drones_have_taken_off", check_history=False).passed
    assert not check(now, "all_drones_have_taken_off", check_history="false",
                     min_altitude=15).passed
    assert not check(ALL, "all_drones_have_taken_off").passed


def test_all_drones_have_landed() -> None:
    both = context(TRUTH, tiny_scenario(DRONES[:2]), 0.0, 60.0)
    leaf = check(both, "all_drones_have_landed")
    assert (leaf.result, leaf.value) == (False, 1)
    only_d1 = context(TRUTH, tiny_scenario(DRONES[:1]), 0.0, 60.0)
    assert check(only_d1, "all_drones_have_landed").passed
    assert check(only_d1, "all_drones_have_landed", check_history=False).passed
    in_flight = context(TRUTH, tiny_scenario(DRONES[:1]), 0.0, 20.0)
    assert not check(in_flight, "all_drones_have_landed", check_history=False).passed


@pytest.mark.parametrize("t0_s", [0.0, 6.0])
def test_events_at_the_window_start_count_and_before_do_not(t0_s: float) -> None:
    ctx = context(TRUTH, SCENARIO, t0_s, 60.0)
    assert check(ctx, "drone_has_taken_off", drone_id="d1").passed
    after = context(TRUTH, SCENARIO, 6.01, 60.0)
    assert not check(after, "drone_has_taken_off", drone_id="d1").passed
