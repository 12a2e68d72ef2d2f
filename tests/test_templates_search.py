"""Search, coordination and assignment templates built on the generated benchmark worlds."""

from __future__ import annotations

import math
import random
import re
from collections.abc import Iterator
from typing import Any

import pytest

from benchmark.authoring.scenarios import FAMILIES, LEVELS, generate_world
from benchmark.authoring.templates import assignment, coordination, search
from benchmark.authoring.templates.base import (
    CATEGORIES,
    SessionView,
    TaskDraft,
    Template,
    TemplateUnfit,
    fmt_xy,
)
from emulator.scenario import scenario_from_dict

try:
    from benchmark.scoring.validators import ENDPOINTS, parse_tree
except ImportError:  # the validators package is optional for these tests
    ENDPOINTS, parse_tree = None, None

TEMPLATES: tuple[Template, ...] = (*search.TEMPLATES, *coordination.TEMPLATES,
                                   *assignment.TEMPLATES)
BY_KEY = {t.key: t for t in TEMPLATES}
SEEDS = range(30)
AREA_ONLY = {"area_sweep", "team_area_sweep", "two_area_search", "search_progress",
             "sweep_with_photos"}

# Plan operations and the keys each one carries.
OPS: dict[str, set[str]] = {
    "takeoff": {"drone", "altitude_m"}, "goto": {"drone", "x", "y", "z"},
    "path": {"drone", "points"}, "land": {"drone"}, "hover": {"drone", "duration_s"},
    "rotate": {"drone", "heading_deg"}, "altitude": {"drone", "altitude_m"},
    "towards": {"drone", "heading_deg", "distance_m"}, "photo": {"drone"},
    "set_home": {"drone"}, "home": {"drone", "altitude_m"}, "charge": {"drone", "station"},
    "message": {"drone", "to", "text"}, "broadcast": {"drone", "text"},
    "reach": {"drone", "target", "altitude_m"},
    "sweep": {"drones", "target", "altitude_m"},
    "visit_targets": {"drones", "targets", "altitude_m"},
}
NUMBER_WORDS = {2: "two", 3: "three"}

_VIEWS: dict[tuple[str, str], SessionView] = {}
_BUILDS: dict[str, list[tuple[SessionView, int, TaskDraft]]] = {}
_UNFIT: dict[str, int] = {}


def _view(family: str, level: str) -> SessionView:
    if (family, level) not in _VIEWS:
        world = generate_world(family, level, 1)
        w, h = world["map_size_m"]
        _VIEWS[family, level] = SessionView(family, scenario_from_dict(world), float(w),
                                            float(h))
    return _VIEWS[family, level]


def _views() -> Iterator[SessionView]:
    for family in FAMILIES:
        for level in LEVELS:
            yield _view(family, level)


def _builds(key: str) -> list[tuple[SessionView, int, TaskDraft]]:
    """Every draft of the template over all fitting sessions and seeds (cached)."""
    if key not in _BUILDS:
        template, out, unfit = BY_KEY[key], [], 0
        for view in _views():
            if not template.fits(view):
                continue
            for seed in SEEDS:
                try:
                    out.append((view, seed, template.build(view, random.Random(seed))))
                except TemplateUnfit:
                    unfit += 1
        _BUILDS[key], _UNFIT[key] = out, unfit
    return _BUILDS[key]


def _drafts(key: str) -> list[TaskDraft]:
    return [draft for _view, _seed, draft in _builds(key)]


def _leaves(node: dict[str, Any]) -> Iterator[dict[str, Any]]:
    if "endpoint" in node:
        yield node
    else:
        for child in node["checks"]:
            yield from _leaves(child)


def _ops(draft: TaskDraft) -> Iterator[dict[str, Any]]:
    for phase in draft.oracle:
        yield from phase


def _mentions(text: str, number: float | str) -> bool:
    if isinstance(number, str):
        return number in text
    shown = f"{number:.0f}" if float(number).is_integer() else f"{number:g}"
    found = re.search(rf"(?<![\d.]){re.escape(shown)}(?![\d])", text) is not None
    return found or (number in NUMBER_WORDS and NUMBER_WORDS[int(number)] in text)


def _required(leaf: dict[str, Any]) -> list[float | str]:
    """The numbers (and coordinate pairs) a leaf needs the instruction to state."""
    e, p = leaf["endpoint"], leaf["parameters"]
    need: list[float | str] = []
    if "x" in p:
        need.append(fmt_xy(p["x"], p["y"]))
    if "at_position" in p:
        need.append(fmt_xy(p["at_position"]["x"], p["at_position"]["y"]))
    if "z" in p:
        need.append(p["z"])
    if e == "drone_has_taken_off" and "max_altitude" in p:
        need.append(p["min_altitude"])
    if e == "all_drones_have_taken_off":
        need.append(p["min_altitude"] + 1.5)
    if e == "drone_has_hovered":
        need.append(p["min_duration"] + 1.0)
    if e in ("two_drones_distance", "drone_group_distance"):
        need.append(p["max_distance"])
    if e == "drone_has_moved_directed_distance":
        need.append(round(p["min_distance"] / 0.9))
    if e == "drone_has_taken_photo" and p.get("min_count", 1) > 1:
        need.append(p["min_count"])
    if e == "target_reached_drone_number":
        need.append(p["expected_count"])
    for share in ("coverage_threshold", "expected_percentage", "expected_progress"):
        if share in p:
            need.append(round(100 * p[share]))
    return need


def _names_needed(leaf: dict[str, Any], view: SessionView) -> list[str]:
    p = leaf["parameters"]
    drones = {d.id: d.name for d in view.drones}
    targets = {t.id: t.name for t in view.scenario.world.targets}
    ids = [p[k] for k in ("drone_id", "drone_1_id", "drone_2_id") if k in p]
    names = [drones[i] for i in [*ids, *p.get("drone_ids", [])]]
    return names + ([targets[p["target_id"]]] if "target_id" in p else [])


@pytest.fixture(params=sorted(BY_KEY))
def key(request: pytest.FixtureRequest) -> str:
    return request.param


def test_catalogue_keys_and_labels() -> None:
    assert [t.key for t in search.TEMPLATES] == [
        "photo_at_point", "inspect_target", "inspect_two_targets", "observe_and_hover",
        "photo_series", "area_sweep", "team_area_sweep", "two_area_search", "search_progress",
        "sweep_with_photos"]
    assert [t.key for t in coordination.TEMPLATES] == [
        "formation_pair", "rendezvous", "fleet_launch", "sweep_line", "double_check_target",
        "cross_check_targets"]
    assert [t.key for t in assignment.TEMPLATES] == [
        "visit_all_targets", "reach_three", "split_inspection"]
    for t in TEMPLATES:
        assert t.category in CATEGORIES
        assert t.difficulty in ("easy", "medium", "hard")
    for module in (search, coordination, assignment):
        assert module.__all__ == ["TEMPLATES"]


def test_fits_follow_the_families() -> None:
    for view in _views():
        # resilience worlds have search areas too, swept by its own templates under faults
        area_family = view.family not in ("target_assignment", "target_tracking", "resilience")
        for k in AREA_ONLY:
            assert BY_KEY[k].fits(view) == area_family, (k, view.family)
        assignment = view.family == "target_assignment"
        assert BY_KEY["visit_all_targets"].fits(view) == assignment
        fixed_family = view.family in ("target_assignment", "resilience")
        six = fixed_family and len(view.points) >= 6 and len(view.drones) >= 3
        assert BY_KEY["split_inspection"].fits(view) == six
        for k in ("photo_at_point", "inspect_target", "formation_pair", "fleet_launch",
                  "sweep_line", "cross_check_targets"):
            assert BY_KEY[k].fits(view), (k, view.family)


@pytest.mark.slow
def test_builds_rarely_unfit(key: str) -> None:
    builds = _builds(key)
    assert len(builds) >= 4 * len(SEEDS)
    assert _UNFIT[key] <= 0.05 * (len(builds) + _UNFIT[key]), _UNFIT[key]


def test_phrasings_are_three_distinct_and_name_everything(key: str) -> None:
    endpoints = set(ENDPOINTS) if ENDPOINTS is not None else set()
    for view, seed, draft in _builds(key):
        assert len(draft.phrasings) == 3 and len(set(draft.phrasings)) == 3, seed
        for text in draft.phrasings:
            assert text.strip() == text and len(text) > 30
            assert not any(name in text for name in endpoints), text
            assert "_" not in text, text
            for leaf in _leaves(draft.checks):
                for name in _names_needed(leaf, view):
                    assert re.search(rf"{re.escape(name)}(?!\d)", text), (name, text)


def test_main_phrasing_states_every_number(key: str) -> None:
    for _v, seed, draft in _builds(key):
        text = draft.phrasings[0]
        for leaf in _leaves(draft.checks):
            for number in _required(leaf):
                assert _mentions(text, number), (seed, leaf, text)


def test_checks_are_well_formed(key: str) -> None:
    for view, seed, draft in _builds(key):
        leaves = list(_leaves(draft.checks))
        assert 1 <= len(leaves) <= 25, (seed, len(leaves))
        for leaf in leaves:
            p = leaf["parameters"]
            for name in ("x", "y", "z", "min_altitude", "max_altitude", "tolerance",
                         "min_duration", "max_distance", "min_distance", "heading"):
                if name in p:
                    assert type(p[name]) is float, (name, p[name])
            for name in ("drone_id", "drone_1_id", "drone_2_id", "target_id"):
                if name in p:
                    assert isinstance(p[name], str)
            if "z" in p:
                assert 10.0 <= p["z"] <= 40.0
            if leaf["endpoint"] == "drone_has_visited_position":
                assert p["tolerance"] == 3.0
            if "at_position" in p:
                assert p["tolerance"] == 5.0
        if parse_tree is not None:
            parse_tree(draft.checks, view.scenario)


def test_oracle_uses_known_ops_and_ids(key: str) -> None:
    for view, seed, draft in _builds(key):
        drones = {d.id for d in view.drones}
        targets = {t.id for t in view.scenario.world.targets}
        assert draft.oracle and all(draft.oracle), seed
        for op in _ops(draft):
            assert op["op"] in OPS, op
            assert set(op) - {"op"} == OPS[op["op"]], op
            for d in [op.get("drone"), *op.get("drones", [])]:
                assert d is None or d in drones, op
            for t in [op.get("target"), *op.get("targets", [])]:
                assert t is None or t in targets, op
            if "drones" in op:
                assert op["drones"] and len(set(op["drones"])) == len(op["drones"])
            for alt in (op.get("z"), op.get("altitude_m")):
                assert alt is None or 10 <= alt <= 40, op
        assert draft.steps >= 1 and draft.flight_m >= 0.0 and draft.hover_s >= 0.0


@pytest.mark.slow
def test_visited_points_and_straight_legs_are_clear(key: str) -> None:
    for view, seed, draft in _builds(key):
        where: dict[str, tuple[float, float, float]] = {}
        for op in _ops(draft):
            d = op.get("drone")
            if op["op"] == "goto":
                assert view.is_free(op["x"], op["y"], avoid_targets=False), (seed, op)
                where[d] = (op["x"], op["y"], float(op["z"]))
            elif op["op"] == "towards":
                x, y, z = where[d]
                heading = math.radians(op["heading_deg"])
                end = (x + op["distance_m"] * math.sin(heading),
                       y + op["distance_m"] * math.cos(heading), z)
                assert view.clear_leg((x, y), end[:2], z), (seed, op)
                assert 20.0 <= end[0] <= view.map_w_m - 20.0
                assert 20.0 <= end[1] <= view.map_h_m - 20.0
                where[d] = end
            elif op["op"] in ("reach", "sweep", "visit_targets", "path"):
                for name in [d, *op.get("drones", [])]:
                    where.pop(name, None)


def test_flight_budget_covers_the_way_out(key: str) -> None:
    for view, seed, draft in _builds(key):
        starts = {d.id: d.position_m[:2] for d in view.drones}
        targets = {t.id: t for t in view.scenario.world.targets}
        for op in _ops(draft):
            if op["op"] == "goto":
                goal = (op["x"], op["y"])
            elif op["op"] == "reach":
                goal = targets[op["target"]].position_m[:2]
            else:
                continue
            assert draft.flight_m >= math.dist(starts[op["drone"]], goal) - 1.0, seed


def test_same_seed_same_draft(key: str) -> None:
    template = BY_KEY[key]
    for view in list(_views())[::4]:
        if not template.fits(view):
            continue
        drafts = []
        for seed in (7, 7, 8):
            try:
                drafts.append(template.build(view, random.Random(seed)))
            except TemplateUnfit:
                drafts.append(None)
        assert drafts[0] == drafts[1]


def test_seeds_vary_the_draft(key: str) -> None:
    builds = _builds(key)
    distinct = {repr((draft.phrasings, draft.checks, draft.oracle)) for _v, _s, draft in builds}
    sessions = {id(view) for view, _s, _d in builds}
    assert len(distinct) > 2 * len(sessions)


# ------------------------------------------------------------------ template specifics
def _checks_of(draft: TaskDraft, endpoint: str) -> list[dict[str, Any]]:
    return [leaf["parameters"] for leaf in _leaves(draft.checks) if leaf["endpoint"] == endpoint]


def test_photo_at_point_photographs_where_it_visits() -> None:
    for draft in _drafts("photo_at_point"):
        (visit,) = _checks_of(draft, "drone_has_visited_position")
        (photo,) = _checks_of(draft, "drone_has_taken_photo")
        assert photo["at_position"] == {"x": visit["x"], "y": visit["y"]}
        assert [op["op"] for op in _ops(draft)] == ["goto", "photo"]


def test_observe_and_hover_holds_one_second_longer_than_checked() -> None:
    for draft in _drafts("observe_and_hover"):
        (hovered,) = _checks_of(draft, "drone_has_hovered")
        hover = next(op for op in _ops(draft) if op["op"] == "hover")
        assert 5 <= hover["duration_s"] <= 20
        assert hovered["min_duration"] == hover["duration_s"] - 1.0
        assert draft.hover_s == hover["duration_s"]


def test_photo_series_points_are_apart() -> None:
    for draft in _drafts("photo_series"):
        points = [(p["x"], p["y"]) for p in _checks_of(draft, "drone_has_visited_position")]
        assert len(points) == 3
        assert min(math.dist(a, b) for a in points for b in points if a != b) >= 50.0


def test_inspections_photograph_each_reached_target() -> None:
    for key in ("inspect_target", "inspect_two_targets", "split_inspection"):
        for view, _seed, draft in _builds(key):
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
    for draft in _drafts("split_inspection"):
        pairs = [(p["drone_id"], p["target_id"])
                 for p in _checks_of(draft, "target_is_reached_by_drone")]
        drones = [d for d, _t in pairs]
        assert len(set(drones)) == 3 and all(drones.count(d) == 2 for d in drones)
        assert len({t for _d, t in pairs}) == 6


def test_single_and_team_sweeps() -> None:
    for draft in _drafts("area_sweep"):
        (sweep,) = [op for op in _ops(draft) if op["op"] == "sweep"]
        assert len(sweep["drones"]) == 1
        assert _checks_of(draft, "target_is_fully_searched")[0]["coverage_threshold"] == 0.95
    for draft in _drafts("team_area_sweep"):
        takeoffs = _checks_of(draft, "drone_has_taken_off")
        (sweep,) = [op for op in _ops(draft) if op["op"] == "sweep"]
        assert 2 <= len(sweep["drones"]) <= 3
        assert {p["drone_id"] for p in takeoffs} == set(sweep["drones"])
        alts = {(p["min_altitude"], p["max_altitude"], p["tolerance"]) for p in takeoffs}
        assert alts == {(float(sweep["altitude_m"]),) * 2 + (1.5,)}
        assert draft.oracle[0] == [{"op": "takeoff", "drone": d, "altitude_m": sweep["altitude_m"]}
                                   for d in sweep["drones"]]


def test_two_area_search_uses_two_to_four_drones_in_disjoint_groups() -> None:
    for draft in _drafts("two_area_search"):
        sweeps = [op for op in _ops(draft) if op["op"] == "sweep"]
        assert len(sweeps) == 2 and sweeps[0]["target"] != sweeps[1]["target"]
        used = sweeps[0]["drones"] + sweeps[1]["drones"]
        assert 2 <= len(used) <= 4 and len(set(used)) == len(used)
        assert {p["target_id"] for p in _checks_of(draft, "target_is_reached")} == {
            s["target"] for s in sweeps}


def test_search_progress_sweeps_every_area_with_the_whole_fleet() -> None:
    for view, _seed, draft in _builds("search_progress"):
        sweeps = [op for op in _ops(draft) if op["op"] == "sweep"]
        assert sorted(s["target"] for s in sweeps) == sorted(a.id for a in view.areas)
        used = [d for s in sweeps for d in s["drones"]]
        assert sorted(used) == sorted(d.id for d in view.drones)
        assert _checks_of(draft, "task_progress") == [{"expected_progress": 0.9}]


def test_search_progress_with_fewer_drones_than_areas() -> None:
    view = _view("area_search", "extreme")
    small = SessionView("area_search", view.scenario, view.map_w_m, view.map_h_m)
    small.drones = small.drones[:3]
    draft = BY_KEY["search_progress"].build(small, random.Random(1))
    sweeps = [op for op in _ops(draft) if op["op"] == "sweep"]
    assert len(sweeps) == len(view.areas) and all(len(s["drones"]) == 1 for s in sweeps)
    assert {s["drones"][0] for s in sweeps} == {d.id for d in small.drones}


def test_sweep_with_photos_has_each_drone_photograph_after_the_sweep() -> None:
    for draft in _drafts("sweep_with_photos"):
        (sweep,) = draft.oracle[0]
        assert len(sweep["drones"]) == 3
        assert draft.oracle[1] == [{"op": "photo", "drone": d} for d in sweep["drones"]]
        assert {p["drone_id"] for p in _checks_of(draft, "drone_has_taken_photo")} == set(
            sweep["drones"])


def test_formation_pair_distance_limit() -> None:
    for draft in _drafts("formation_pair"):
        a, b = ((p["x"], p["y"]) for p in _checks_of(draft, "drone_has_visited_position"))
        (pair,) = _checks_of(draft, "two_drones_distance")
        assert 9.0 <= math.dist(a, b) <= 21.0
        assert pair["max_distance"] == math.ceil(math.dist(a, b)) + 3


def test_rendezvous_slots_surround_the_spot() -> None:
    for draft in _drafts("rendezvous"):
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
    for view, _seed, draft in _builds("fleet_launch"):
        takeoffs = draft.oracle[0]
        assert sorted(op["drone"] for op in takeoffs) == sorted(d.id for d in view.drones)
        (launched,) = _checks_of(draft, "all_drones_have_taken_off")
        assert launched["min_altitude"] == takeoffs[0]["altitude_m"] - 1.5


def test_sweep_line_checks_match_the_straight_legs() -> None:
    for draft in _drafts("sweep_line"):
        ops = list(_ops(draft))
        legs = {(op["drone"], op["heading_deg"]): op["distance_m"]
                for op in ops if op["op"] == "towards"}
        directed = _checks_of(draft, "drone_has_moved_directed_distance")
        assert len(directed) == len(legs) and 6 <= len(legs) <= 8
        for p in directed:
            assert p["min_distance"] == round(0.9 * legs[p["drone_id"], p["heading"]], 1)
            assert p["tolerance"] == 5.0


def test_double_and_cross_checks() -> None:
    for draft in _drafts("double_check_target"):
        (count,) = _checks_of(draft, "target_reached_drone_number")
        assert count["expected_count"] == 2
        reached = _checks_of(draft, "target_is_reached_by_drone")
        assert {p["target_id"] for p in reached} == {count["target_id"]}
        assert len({p["drone_id"] for p in reached}) == 2
    for draft in _drafts("cross_check_targets"):
        pairs = {(p["drone_id"], p["target_id"])
                 for p in _checks_of(draft, "target_is_reached_by_drone")}
        drones, targets = {d for d, _ in pairs}, {t for _, t in pairs}
        assert len(drones) == 2 and len(targets) == 2 and len(pairs) == 4


def test_assignment_visits() -> None:
    for view, _seed, draft in _builds("visit_all_targets"):
        (visit,) = list(_ops(draft))
        assert visit["op"] == "visit_targets"
        assert sorted(visit["drones"]) == sorted(d.id for d in view.drones)
        assert sorted(visit["targets"]) == sorted(t.id for t in view.points)
        assert _checks_of(draft, "task_progress") == [{"expected_progress": 0.95}]
    for draft in _drafts("reach_three"):
        (visit,) = list(_ops(draft))
        reached = [p["target_id"] for p in _checks_of(draft, "target_is_reached")]
        assert len(set(reached)) == 3 and sorted(visit["targets"]) == sorted(reached)


def test_too_few_targets_is_unfit() -> None:
    view = _view("target_assignment", "easy")
    bare = SessionView("target_assignment", view.scenario, view.map_w_m, view.map_h_m)
    bare.points = bare.points[:1]
    with pytest.raises(TemplateUnfit, match="needs 2 fixed or area targets"):
        BY_KEY["inspect_two_targets"].build(bare, random.Random(0))
    bare.points = []
    assert not BY_KEY["reach_three"].fits(bare)
