"""Search, coordination and assignment templates built on the generated benchmark worlds."""

from __future__ import annotations

import math
import random
import re
from typing import Any

import pytest

from benchmark.authoring.templates import assignment, coordination, search
from benchmark.authoring.templates.base import (
    CATEGORIES,
    SessionView,
    TemplateUnfit,
    fmt_xy,
)

try:
    from benchmark.scoring.validators import ENDPOINTS, parse_tree
except ImportError:  # the validators package is optional for these tests
    ENDPOINTS, parse_tree = None, None

from tests.template_builds import (
    BY_KEY,
    SEEDS,
    TEMPLATES,
    UNFIT,
    check_leaves,
    drafts_built,
    plan_ops,
    views,
)

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
    for view in views():
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
    builds = drafts_built(key)
    assert len(builds) >= 4 * len(SEEDS)
    assert UNFIT[key] <= 0.05 * (len(builds) + UNFIT[key]), UNFIT[key]


def test_phrasings_are_three_distinct_and_name_everything(key: str) -> None:
    endpoints = set(ENDPOINTS) if ENDPOINTS is not None else set()
    for view, seed, draft in drafts_built(key):
        assert len(draft.phrasings) == 3 and len(set(draft.phrasings)) == 3, seed
        for text in draft.phrasings:
            assert text.strip() == text and len(text) > 30
            assert not any(name in text for name in endpoints), text
            assert "_" not in text, text
            for leaf in check_leaves(draft.checks):
                for name in _names_needed(leaf, view):
                    assert re.search(rf"{re.escape(name)}(?!\d)", text), (name, text)


def test_main_phrasing_states_every_number(key: str) -> None:
    for _v, seed, draft in drafts_built(key):
        text = draft.phrasings[0]
        for leaf in check_leaves(draft.checks):
            for number in _required(leaf):
                assert _mentions(text, number), (seed, leaf, text)


def test_checks_are_well_formed(key: str) -> None:
    for view, seed, draft in drafts_built(key):
        leaves = list(check_leaves(draft.checks))
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
    for view, seed, draft in drafts_built(key):
        drones = {d.id for d in view.drones}
        targets = {t.id for t in view.scenario.world.targets}
        assert draft.oracle and all(draft.oracle), seed
        for op in plan_ops(draft):
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
    for view, seed, draft in drafts_built(key):
        where: dict[str, tuple[float, float, float]] = {}
        for op in plan_ops(draft):
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
    for view, seed, draft in drafts_built(key):
        starts = {d.id: d.position_m[:2] for d in view.drones}
        targets = {t.id: t for t in view.scenario.world.targets}
        for op in plan_ops(draft):
            if op["op"] == "goto":
                goal = (op["x"], op["y"])
            elif op["op"] == "reach":
                goal = targets[op["target"]].position_m[:2]
            else:
                continue
            assert draft.flight_m >= math.dist(starts[op["drone"]], goal) - 1.0, seed


def test_same_seed_same_draft(key: str) -> None:
    template = BY_KEY[key]
    for view in list(views())[::4]:
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
    builds = drafts_built(key)
    distinct = {repr((draft.phrasings, draft.checks, draft.oracle)) for _v, _s, draft in builds}
    sessions = {id(view) for view, _s, _d in builds}
    assert len(distinct) > 2 * len(sessions)
