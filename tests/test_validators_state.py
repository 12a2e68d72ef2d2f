"""Current-state checks: the ground truth at the end of the window."""

from __future__ import annotations

import pytest

from emulator.world import Obstacle, Target
from tests.scenario_fixtures import tiny_scenario, vehicle
from tests.test_validators_fixtures import check, context, event, log, rows

TARGETS = (
    Target.disc("t1", "On top", "fixed", (100.0, 0.0, 0.0), 5.0),
    Target.disc("t2", "Far", "fixed", (200.0, 0.0, 0.0), 5.0),
    Target.disc("t3", "Task radius", "fixed", (120.0, 0.0, 0.0), 1.0),
    Target.disc("t4", "Perceived", "fixed", (140.0, 0.0, 0.0), 1.0),
)
OBSTACLES = (
    Obstacle.polygon("o1", "Box", [(110.0, -5.0), (120.0, -5.0), (120.0, 5.0), (110.0, 5.0)]),
    Obstacle.disc("o2", "Tower", (300.0, 0.0), 10.0),
)
SCENARIO = tiny_scenario([vehicle(1), vehicle(2, 50.0), vehicle(3, 60.0), vehicle(4, 0.0, 80.0)],
                    targets=TARGETS, obstacles=OBSTACLES)
# d1: climbs to 10 m over (0, 0) by t=5, flies east to (100, 0) by t=15, hovers until t=30.
# d2, d3: on the ground. d4: only recorded from t=5, heading 358.
TRUTH = log(
    {
        "d1": rows([(0, 0, 0, 0), (5, 0, 0, 10), (15, 100, 0, 10)], t_end_s=30.0, yaw_deg=90.0),
        "d2": rows([(0, 50, 0, 0)], t_end_s=30.0, battery=(80.0, 0.0)),
        "d3": rows([(0, 60, 0, 0)], t_end_s=30.0),
        "d4": rows([(5, 0, 80, 0)], t_end_s=30.0, yaw_deg=358.0),
    },
    [event(20.0, "d1", "home", position_m=[100.0, 0.5, 0.0]),
     event(40.0, "d2", "home", position_m=[0.0, 0.0, 0.0])],
    end_t_s=30.0,
)
END = context(TRUTH, SCENARIO, 0.0, 30.0)
MID_FLIGHT = context(TRUTH, SCENARIO, 0.0, 10.01)


def test_drone_position_2d_and_3d() -> None:
    assert check(END, "drone_position", drone_id="d1", x=100, y=0).passed
    leaf = check(END, "drone_position", drone_id="d1", x=103, y=0)
    assert (leaf.result, leaf.value) == (False, 3.0)
    assert check(END, "drone_position", drone_id="d1", x=100, y=0, z=10).passed
    leaf = check(END, "drone_position", drone_id="d1", x=100, y=0, z=0, tolerance=5)
    assert (leaf.result, leaf.value) == (False, 10.0)


def test_drone_position_interpolates_between_samples_at_t1() -> None:
    leaf = check(MID_FLIGHT, "drone_position", drone_id="d1", x=50.1, y=0, tolerance=1e-6)
    assert leaf.passed, leaf


def test_drone_status_derived_from_truth() -> None:
    assert check(END, "drone_status", drone_id="d1", expected_status="hovering").value == (
        "hovering")
    assert not check(END, "drone_status", drone_id="d1", expected_status="moving").passed
    assert check(END, "drone_status", drone_id="d2", expected_status="idle").passed
    assert check(END, "drone_status", drone_id="d2", expected_status="ready").passed
    assert not check(END, "drone_status", drone_id="d2", expected_status="flying").passed
    leaf = check(MID_FLIGHT, "drone_status", drone_id="d1", expected_status="flying")
    assert (leaf.passed, leaf.value) == (True, "moving")
    assert not check(MID_FLIGHT, "drone_status", drone_id="d1", expected_status="hovering").passed


def test_drone_battery_level() -> None:
    assert check(END, "drone_battery_level", drone_id="d2", min_level=75).passed
    leaf = check(END, "drone_battery_level", drone_id="d2", min_level=85)
    assert (leaf.result, leaf.value) == (False, 80.0)


def test_drone_heading_with_wrap_around() -> None:
    assert check(END, "drone_heading", drone_id="d1", expected_heading=92).passed
    assert not check(END, "drone_heading", drone_id="d1", expected_heading=270).passed
    assert check(END, "drone_heading", drone_id="d4", expected_heading=2, tolerance=5).passed
    assert not check(END, "drone_heading", drone_id="d4", expected_heading=10).passed


def test_drone_over_height_and_altitude() -> None:
    assert check(END, "drone_over_height", drone_id="d1", min_height=10.05).passed
    assert not check(END, "drone_over_height", drone_id="d1", min_height=10.5).passed
    assert check(END, "drone_altitude", drone_id="d1", expected_altitude=10.4).passed
    leaf = check(END, "drone_altitude", drone_id="d1", expected_altitude=12)
    assert (leaf.result, leaf.value) == (False, 10.0)


def test_drone_on_ground_and_hovering() -> None:
    assert check(END, "drone_on_ground", drone_id="d2").passed
    assert not check(END, "drone_on_ground", drone_id="d1").passed
    assert check(END, "drone_on_ground", drone_id="d1", expect=False).passed
    assert check(END, "drone_hovering", drone_id="d1").passed
    assert not check(MID_FLIGHT, "drone_hovering", drone_id="d1").passed
    assert not check(END, "drone_hovering", drone_id="d2").passed


def test_all_drones_on_ground_and_hovering() -> None:
    at_start = context(TRUTH, tiny_scenario([vehicle(1), vehicle(2, 50.0)]), 0.0, 0.0)
    leaf = check(at_start, "all_drones_on_ground")
    assert (leaf.result, leaf.value) == (True, 2)
    two = context(TRUTH, tiny_scenario([vehicle(1), vehicle(2, 50.0)]), 0.0, 30.0)
    leaf = check(two, "all_drones_on_ground")
    assert (leaf.result, leaf.value) == (False, 1)
    assert (check(two, "all_drones_hovering").result, check(two, "all_drones_hovering").value) \
        == (False, 1)
    only_d1 = context(TRUTH, tiny_scenario([vehicle(1)]), 0.0, 30.0)
    assert check(only_d1, "all_drones_hovering").passed


def test_drone_at_home_follows_home_events_up_to_t1() -> None:
    before = context(TRUTH, SCENARIO, 0.0, 19.0)
    leaf = check(before, "drone_at_home", drone_id="d1")
    assert (leaf.result, leaf.value) == (False, 100.0)
    leaf = check(END, "drone_at_home", drone_id="d1")
    assert (leaf.result, leaf.value) == (True, 0.5)
    assert check(END, "drone_at_home", drone_id="d2", tolerance=0.0).passed  # later home ignored


def test_drone_in_target_uses_the_footprint() -> None:
    assert check(END, "drone_in_target", drone_id="d1", target_id="t1").passed
    leaf = check(END, "drone_in_target", drone_id="d1", target_id="t2")
    assert (leaf.result, leaf.value) == (False, 95.0)


def test_target_within_distances() -> None:
    assert check(END, "target_within_drone_distance", drone_id="d1", target_id="t2",
                 max_distance=100).passed
    assert not check(END, "target_within_drone_distance", drone_id="d1", target_id="t2",
                     max_distance=90).passed
    leaf = check(END, "target_within_drone_task_radius", drone_id="d1", target_id="t3")
    assert (leaf.result, leaf.value) == (True, 19.0)
    assert not check(END, "target_within_drone_task_radius", drone_id="d1", target_id="t2").passed
    assert check(END, "target_within_drone_perceived_radius", drone_id="d1",
                 target_id="t4").passed
    assert not check(END, "target_within_drone_perceived_radius", drone_id="d1",
                     target_id="t2").passed


def test_obstacle_within_distances() -> None:
    leaf = check(END, "obstacle_within_drone_distance", drone_id="d1", obstacle_id="o1",
                 max_distance=10.5)
    assert (leaf.result, leaf.value) == (True, 10.0)
    assert not check(END, "obstacle_within_drone_distance", drone_id="d1", obstacle_id="o1",
                     max_distance=9).passed
    assert check(END, "obstacle_within_drone_perceived_radius", drone_id="d1",
                 obstacle_id="o1").passed
    leaf = check(END, "obstacle_within_drone_perceived_radius", drone_id="d1", obstacle_id="o2")
    assert leaf.result is False
    assert leaf.value == pytest.approx(190.0, abs=0.01)


def test_two_drones_distance_is_3d() -> None:
    leaf = check(END, "two_drones_distance", drone_1_id="d1", drone_2_id="d2", max_distance=60)
    assert leaf.result is True
    assert leaf.value == pytest.approx((50.0**2 + 10.0**2) ** 0.5, abs=1e-3)
    assert not check(END, "two_drones_distance", drone_1_id="d1", drone_2_id="d2",
                     max_distance=40).passed
    assert not check(END, "two_drones_distance", drone_1_id="d1", drone_2_id="d2",
                     min_distance=55).passed


def test_drone_group_distance_modes() -> None:
    ids = ["d1", "d2", "d3"]
    leaf = check(END, "drone_group_distance", drone_ids=ids, max_distance=45)
    assert (leaf.result, leaf.value) == (False, 2)
    leaf = check(END, "drone_group_distance", drone_ids=ids, max_distance=45, mode="any_pair")
    assert (leaf.result, leaf.value) == (True, 2)
    assert check(END, "drone_group_distance", drone_ids=ids, min_distance=5).passed


def test_a_drone_without_samples_yet_gives_an_error_not_an_exception() -> None:
    early = context(TRUTH, SCENARIO, 0.0, 2.0)
    leaf = check(early, "drone_altitude", drone_id="d4", expected_altitude=0)
    assert leaf.result is None and not leaf.passed
    assert "no ground-truth samples for drone 'd4'" in (leaf.error or "")
