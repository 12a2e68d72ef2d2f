"""What each search, coordination and assignment template asks for in particular: its checks,
oracle plan and numbers, over every draft built on the generated benchmark worlds."""

from __future__ import annotations

import math
import random
from typing import Any

import pytest

from benchmark.authoring.templates.base import SessionView, TaskDraft, TemplateUnfit
from tests.template_builds import BY_KEY, check_leaves, drafts, drafts_built, plan_ops, view_of


def _checks_of(draft: TaskDraft, endpoint: str) -> list[dict[str, Any]]:
    return [leaf["parameters"] for leaf in check_leaves(draft.checks)
            if leaf["endpoint"] == endpoint]


def test_photo_at_point_photographs_where_it_visits() -> None:
    for draft in drafts("photo_at_point"):
        (visit,) = _checks_of(draft, "drone_has_visited_position")
        (photo,) = _checks_of(draft, "drone_has_taken_photo")
        assert photo["at_position"] == {"x": visit["x"], "y": visit["y"]}
        assert [op["op"] for op in plan_ops(draft)] == ["goto", "photo"]


def test_observe_and_hover_holds_one_second_longer_than_checked() -> None:
    for draft in drafts("observe_and_hover"):
        (hovered,) = _checks_of(draft, "drone_has_hovered")
        hover = next(op for op in plan_ops(draft) if op["op"] == "hover")
        assert 5 <= hover["duration_s"] <= 20
        assert hovered["min_duration"] == hover["duration_s"] - 1.0
        assert draft.hover_s == hover["duration_s"]


def test_photo_series_points_are_apart() -> None:
    for draft in drafts("photo_series"):
        points = [(p["x"], p["y"]) for p in _checks_of(draft, "drone_has_visited_position")]
        assert len(points) == 3
        assert min(math.dist(a, b) for a in points for b in points if a != b) >= 50.0


def test_inspections_photograph_each_reached_target() -> None:
    for key in ("inspect_target", "inspect_two_targets", "split_inspection"):
        for view, _seed, draft in drafts_built(key):
            reached = {(p["drone_id"], p["target_id"])
                       for p in _checks_of(draft, "target_is_reached_by_drone")}
            photos = {(p["drone_id"], p["target_id"])
                      for p in _checks_of(draft, "target_in_photo_taken_by_drone")}
            assert reached == photos
            ops = [op for phase in draft.oracle for op in phase]
            for drone, target in reached:
                mine = [op for op in ops if op["drone"] == drone]
                k = mine.index({"op": "reach", "drone": drone, "target": target,
                                "altitude_m": mine[0]["altitude_m"]})
                assert mine[k + 1] == {"op": "photo", "drone": drone}
                assert view.scenario.world.target(target).kind in ("fixed", "circle", "polygon")


def test_split_inspection_gives_two_targets_to_each_drone() -> None:
    for draft in drafts("split_inspection"):
        pairs = [(p["drone_id"], p["target_id"])
                 for p in _checks_of(draft, "target_is_reached_by_drone")]
        drones = [d for d, _t in pairs]
        assert len(set(drones)) == 3 and all(drones.count(d) == 2 for d in drones)
        assert len({t for _d, t in pairs}) == 6


def test_single_and_team_sweeps() -> None:
    for draft in drafts("area_sweep"):
        (sweep,) = [op for op in plan_ops(draft) if op["op"] == "sweep"]
        assert len(sweep["drones"]) == 1
        assert _checks_of(draft, "target_is_fully_searched")[0]["coverage_threshold"] == 0.95
    for draft in drafts("team_area_sweep"):
        takeoffs = _checks_of(draft, "drone_has_taken_off")
        (sweep,) = [op for op in plan_ops(draft) if op["op"] == "sweep"]
        assert 2 <= len(sweep["drones"]) <= 3
        assert {p["drone_id"] for p in takeoffs} == set(sweep["drones"])
        alts = {(p["min_altitude"], p["max_altitude"], p["tolerance"]) for p in takeoffs}
        assert alts == {(float(sweep["altitude_m"]),) * 2 + (1.5,)}
        assert draft.oracle[0] == [{"op": "takeoff", "drone": d, "altitude_m": sweep["altitude_m"]}
                                   for d in sweep["drones"]]


def test_two_area_search_uses_two_to_four_drones_in_disjoint_groups() -> None:
    for draft in drafts("two_area_search"):
        sweeps = [op for op in plan_ops(draft) if op["op"] == "sweep"]
        assert len(sweeps) == 2 and sweeps[0]["target"] != sweeps[1]["target"]
        used = sweeps[0]["drones"] + sweeps[1]["drones"]
        assert 2 <= len(used) <= 4 and len(set(used)) == len(used)
        assert {p["target_id"] for p in _checks_of(draft, "target_is_reached")} == {
            s["target"] for s in sweeps}


def test_search_progress_sweeps_every_area_with_the_whole_fleet() -> None:
    for view, _seed, draft in drafts_built("search_progress"):
        sweeps = [op for op in plan_ops(draft) if op["op"] == "sweep"]
        assert sorted(s["target"] for s in sweeps) == sorted(a.id for a in view.areas)
        used = [d for s in sweeps for d in s["drones"]]
        assert sorted(used) == sorted(d.id for d in view.drones)
        assert _checks_of(draft, "task_progress") == [{"expected_progress": 0.9}]


def test_search_progress_with_fewer_drones_than_areas() -> None:
    view = view_of("area_search", "extreme")
    small = SessionView("area_search", view.scenario, view.map_w_m, view.map_h_m)
    small.drones = small.drones[:3]
    draft = BY_KEY["search_progress"].build(small, random.Random(1))
    sweeps = [op for op in plan_ops(draft) if op["op"] == "sweep"]
    assert len(sweeps) == len(view.areas) and all(len(s["drones"]) == 1 for s in sweeps)
    assert {s["drones"][0] for s in sweeps} == {d.id for d in small.drones}


def test_sweep_with_photos_has_each_drone_photograph_after_the_sweep() -> None:
    for draft in drafts("sweep_with_photos"):
        (sweep,) = draft.oracle[0]
        assert len(sweep["drones"]) == 3
        assert draft.oracle[1] == [{"op": "photo", "drone": d} for d in sweep["drones"]]
        assert {p["drone_id"] for p in _checks_of(draft, "drone_has_taken_photo")} == set(
            sweep["drones"])


def test_formation_pair_distance_limit() -> None:
    for draft in drafts("formation_pair"):
        a, b = ((p["x"], p["y"]) for p in _checks_of(draft, "drone_has_visited_position"))
        (pair,) = _checks_of(draft, "two_drones_distance")
        assert 9.0 <= math.dist(a, b) <= 21.0
        assert pair["max_distance"] == math.ceil(math.dist(a, b)) + 3


def test_rendezvous_slots_surround_the_spot() -> None:
    for draft in drafts("rendezvous"):
        visits = _checks_of(draft, "drone_has_visited_position")
        assert 3 <= len(visits) <= 4
        assert len({p["z"] for p in visits}) == len(visits)
        cx = sum(p["x"] for p in visits) / len(visits)
        cy = sum(p["y"] for p in visits) / len(visits)
        assert all(math.dist((cx, cy), (p["x"], p["y"])) <= 28.0 for p in visits)
        (group,) = _checks_of(draft, "drone_group_distance")
        assert group["mode"] == "all_pairs" and group["max_distance"] == 45.0
        assert sorted(group["drone_ids"]) == sorted(p["drone_id"] for p in visits)
        for p in visits:  # every pair of slots is well inside the limit
            for q in visits:
                assert math.dist((p["x"], p["y"], p["z"]), (q["x"], q["y"], q["z"])) < 40.0


def test_fleet_launch_takes_off_every_drone() -> None:
    for view, _seed, draft in drafts_built("fleet_launch"):
        takeoffs = draft.oracle[0]
        assert sorted(op["drone"] for op in takeoffs) == sorted(d.id for d in view.drones)
        (launched,) = _checks_of(draft, "all_drones_have_taken_off")
        assert launched["min_altitude"] == takeoffs[0]["altitude_m"] - 1.5


def test_sweep_line_checks_match_the_straight_legs() -> None:
    for draft in drafts("sweep_line"):
        ops = list(plan_ops(draft))
        legs = {(op["drone"], op["heading_deg"]): op["distance_m"]
                for op in ops if op["op"] == "towards"}
        directed = _checks_of(draft, "drone_has_moved_directed_distance")
        assert len(directed) == len(legs) and 6 <= len(legs) <= 8
        for p in directed:
            assert p["min_distance"] == round(0.9 * legs[p["drone_id"], p["heading"]], 1)
            assert p["tolerance"] == 5.0


def test_double_and_cross_checks() -> None:
    for draft in drafts("double_check_target"):
        (count,) = _checks_of(draft, "target_reached_drone_number")
        assert count["expected_count"] == 2
        reached = _checks_of(draft, "target_is_reached_by_drone")
        assert {p["target_id"] for p in reached} == {count["target_id"]}
        assert len({p["drone_id"] for p in reached}) == 2
    for draft in drafts("cross_check_targets"):
        pairs = {(p["drone_id"], p["target_id"])
                 for p in _checks_of(draft, "target_is_reached_by_drone")}
        drones, targets = {d for d, _ in pairs}, {t for _, t in pairs}
        assert len(drones) == 2 and len(targets) == 2 and len(pairs) == 4


def test_assignment_visits() -> None:
    for view, _seed, draft in drafts_built("visit_all_targets"):
        (visit,) = list(plan_ops(draft))
        assert visit["op"] == "visit_targets"
        assert sorted(visit["drones"]) == sorted(d.id for d in view.drones)
        assert sorted(visit["targets"]) == sorted(t.id for t in view.points)
        assert _checks_of(draft, "task_progress") == [{"expected_progress": 0.95}]
    for draft in drafts("reach_three"):
        (visit,) = list(plan_ops(draft))
        reached = [p["target_id"] for p in _checks_of(draft, "target_is_reached")]
        assert len(set(reached)) == 3 and sorted(visit["targets"]) == sorted(reached)


def test_too_few_targets_is_unfit() -> None:
    view = view_of("target_assignment", "easy")
    bare = SessionView("target_assignment", view.scenario, view.map_w_m, view.map_h_m)
    bare.points = bare.points[:1]
    with pytest.raises(TemplateUnfit, match="needs 2 fixed or area targets"):
        BY_KEY["inspect_two_targets"].build(bare, random.Random(0))
    bare.points = []
    assert not BY_KEY["reach_three"].fits(bare)
