"""Target checks: continuous reaching, visits, tracking, coverage and task progress."""

from __future__ import annotations

import numpy as np
import pytest

from benchmark.scoring.validators import CheckContext, evaluate, parse_tree
from emulator.world import Target
from tests.scenario_fixtures import tiny_scenario, vehicle
from tests.test_validators_fixtures import check, context, lawnmower, log, rows

SQUARE = [(0.0, 0.0), (100.0, 0.0), (100.0, 100.0), (0.0, 100.0)]
FAR_SQUARE = [(500.0, 500.0), (600.0, 500.0), (600.0, 600.0), (500.0, 600.0)]


def _targets() -> list[Target]:
    return [
        Target.disc("near", "14 m off the pass", "fixed", (100.0, 15.0, 0.0), 1.0),
        Target.disc("off", "24 m off the pass", "fixed", (100.0, 25.0, 0.0), 1.0),
        Target.disc("end", "End of the pass", "fixed", (200.0, 0.0, 0.0), 1.0),
        Target.disc("mover", "Moving target", "moving", (300.0, -100.0, 0.0), 1.0),
        Target.disc("station", "Charger", "waypoint", (-50.0, -50.0, 0.0), 3.0,
                    charge_rate_pct_s=0.5),
    ]


# d1: two samples only, a 200 m straight pass at 10 m altitude (t 0-10), then holds.
# d2: shuttles along y = 0 between x 0 and 200 three times at 10 m (t 0-60).
# d3: hovers 12 s in range of the moving target (t 10-22), away before and after.
# d4: drives on the ground through 'end' (never airborne).
D1 = np.array([[0, 0, 0, 10, 0, 100], [10, 200, 0, 10, 0, 99]], dtype=float)
D2 = rows([(0, 0, 0, 10), (20, 200, 0, 10), (40, 0, 0, 10), (60, 200, 0, 10)])
D3 = rows([(0, 300, 100, 10), (10, 300, -85, 10), (22, 300, -85, 10), (30, 300, 100, 10)],
          t_end_s=60.0)
D4 = rows([(0, 150, 0, 0), (20, 250, 0, 0)], t_end_s=60.0)
TRUTH = log({"d1": D1, "d2": D2, "d3": D3, "d4": D4}, end_t_s=60.0)
DRONES = [vehicle(1), vehicle(2), vehicle(3), vehicle(4)]
REACH = context(TRUTH, tiny_scenario(DRONES, targets=_targets()), 0.0, 60.0)


def test_a_pass_between_two_samples_reaches_a_target_within_the_task_radius() -> None:
    leaf = check(REACH, "target_is_reached_by_drone", target_id="near", drone_id="d1")
    assert (leaf.result, leaf.value) == (True, 1)
    leaf = check(REACH, "target_is_reached_by_drone", target_id="off", drone_id="d1")
    assert (leaf.result, leaf.value) == (False, 0)


def test_visits_count_separate_entries() -> None:
    leaf = check(REACH, "target_is_reached_by_drone", target_id="end", drone_id="d2")
    assert (leaf.result, leaf.value) == (True, 2)
    leaf = check(REACH, "target_is_reached_by_drone", target_id="near", drone_id="d2")
    assert leaf.value == 3


def test_only_airborne_flight_reaches() -> None:
    assert not check(REACH, "target_is_reached_by_drone", target_id="end",
                     drone_id="d4").passed


def test_target_is_reached_and_drone_number() -> None:
    leaf = check(REACH, "target_is_reached", target_id="end")
    assert (leaf.result, leaf.value) == (True, 2)  # d1 and d2, not d4
    assert not check(REACH, "target_is_reached", target_id="off").passed
    assert check(REACH, "target_reached_drone_number", target_id="end", expected_count=2).passed
    leaf = check(REACH, "target_reached_drone_number", target_id="end", expected_count=3)
    assert (leaf.result, leaf.value) == (False, 2)
    assert check(REACH, "target_reached_drone_number", target_id="near").passed
    assert not check(REACH, "target_reached_drone_number", target_id="off").passed


def test_reaches_before_the_window_do_not_count() -> None:
    later = context(TRUTH, REACH.scenario, 10.5, 60.0)
    assert not check(later, "target_is_reached_by_drone", target_id="near", drone_id="d1").passed
    leaf = check(later, "target_is_reached_by_drone", target_id="end", drone_id="d2")
    assert leaf.value == 2
    last_leg = context(TRUTH, REACH.scenario, 41.0, 60.0)
    assert check(last_leg, "target_is_reached_by_drone", target_id="end", drone_id="d2").value \
        == 1


def test_moving_target_tracked_longest_period() -> None:
    leaf = check(REACH, "moving_target_tracked", target_id="mover", min_duration=10)
    assert leaf.result is True
    # In range while y <= -79 (20 m task radius + 1 m target radius): about 12.6 s, and the
    # reference's tracking window keeps it tracked 10 s longer.
    assert leaf.value == pytest.approx(12.0 + 2 * 6 / 18.5 + 10.0, abs=0.05)
    assert check(REACH, "moving_target_tracked", target_id="mover", min_duration=22).passed
    assert not check(REACH, "moving_target_tracked", target_id="mover", min_duration=23).passed
    leaf = check(REACH, "moving_target_tracked", target_id="mover", drone_id="d1")
    assert (leaf.result, leaf.value) == (False, 0.0)


SEARCH = [Target.polygon("square", "Square", SQUARE),
          Target.polygon("far", "Far square", FAR_SQUARE),
          Target.disc("disc", "Disc area", "circle", (-200.0, 0.0, 0.0), 10.0),
          Target.disc("station", "Charger", "waypoint", (-50.0, -50.0, 0.0), 3.0,
                      charge_rate_pct_s=0.5)]


def _coverage_context(y1: float, *, targets: list[Target] = SEARCH,
                      task_type: str = "area_search") -> CheckContext:
    keys = lawnmower(0.0, 12.5, 100.0, y1, 25.0, z_m=15.0, speed_m_s=10.0)
    hover = rows([(0, -200, 0, 0), (2, -200, 0, 10)], t_end_s=keys[-1][0])
    truth = log({"d1": rows(keys), "d2": hover})
    scen = tiny_scenario([vehicle(1, task_radius_m=12.5), vehicle(2, task_radius_m=20.0)],
                    targets=targets, task_type=task_type)
    return context(truth, scen, 0.0, keys[-1][0])


def test_lawnmower_over_the_whole_square_covers_it() -> None:
    ctx = _coverage_context(87.5)
    leaf = check(ctx, "target_is_fully_searched", target_id="square")
    assert leaf.result is True
    assert leaf.value == pytest.approx(1.0, abs=0.005)
    assert check(ctx, "target_is_fully_searched", target_id="disc").value == pytest.approx(1.0)
    leaf = check(ctx, "target_is_fully_searched", target_id="far", coverage_threshold=0.01)
    assert (leaf.result, leaf.value) == (False, 0.0)


def test_lawnmower_over_half_the_square_covers_half() -> None:
    ctx = _coverage_context(37.5)
    leaf = check(ctx, "target_searched_area_percentage", target_id="square",
                 expected_percentage=0.45)
    assert leaf.result is True
    assert leaf.value == pytest.approx(0.5, abs=0.01)
    assert not check(ctx, "target_searched_area_percentage", target_id="square",
                     expected_percentage=0.55).passed
    assert not check(ctx, "target_is_fully_searched", target_id="square").passed


def test_point_targets_are_covered_once_reached() -> None:
    assert check(REACH, "target_is_fully_searched", target_id="near").value == 1.0
    assert check(REACH, "target_searched_area_percentage", target_id="off",
                 expected_percentage=0.0).value == 0.0


def test_task_progress_and_done_for_area_search() -> None:
    ctx = _coverage_context(87.5)  # square and disc covered, far square not; station excluded
    leaf = check(ctx, "task_progress", expected_progress=0.66)
    assert (leaf.result, leaf.value) == (True, 0.66)
    assert not check(ctx, "task_progress", expected_progress=0.67).passed
    leaf = check(ctx, "task_done")
    assert (leaf.result, leaf.value) == (False, 0.66)
    done = _coverage_context(87.5, targets=[t for t in SEARCH if t.id != "far"])
    assert check(done, "task_done").passed
    assert check(done, "task_progress", expected_progress=0.99).passed


@pytest.mark.parametrize(("task_type", "progress"), [("target_assignment", 0.66),
                                                     ("others", 2 / 3)])
def test_task_progress_for_target_families(task_type: str, progress: float) -> None:
    targets = [t for t in _targets() if t.id in ("near", "end", "off", "station")]
    ctx = context(TRUTH, tiny_scenario(DRONES, targets=targets, task_type=task_type), 0.0, 60.0)
    leaf = check(ctx, "task_progress", expected_progress=0.66)
    assert leaf.result is True
    assert leaf.value == pytest.approx(progress, abs=1e-4)
    assert not check(ctx, "task_progress", expected_progress=0.7).passed
    assert not check(ctx, "task_done").passed
    reached = [t for t in targets if t.id != "off"]
    ctx = context(TRUTH, tiny_scenario(DRONES, targets=reached, task_type=task_type), 0.0, 60.0)
    assert check(ctx, "task_done").passed
    assert check(ctx, "task_progress", expected_progress=1.0).passed


def test_evaluation_is_deterministic() -> None:
    tree = parse_tree({"checks": [
        {"endpoint": "target_is_reached", "parameters": {"target_id": "square"}},
        {"endpoint": "target_is_fully_searched", "parameters": {"target_id": "square"}},
        {"endpoint": "task_progress", "parameters": {"expected_progress": 0.5}},
    ]})
    first = evaluate(tree, _coverage_context(87.5)).to_json()
    second = evaluate(tree, _coverage_context(87.5)).to_json()
    assert first == second
    assert first["passed"] is True
