"""Navigation, delivery, battery and communication templates, built on generated sessions."""

from __future__ import annotations

import contextlib
import functools
import itertools
import math
import random
import re
from collections.abc import Iterator
from typing import Any

import pytest
import shapely

from benchmark.authoring.scenarios import FAMILIES, LEVELS, generate_world
from benchmark.authoring.templates import battery, communication, delivery, navigation
from benchmark.authoring.templates.base import (
    CATEGORIES,
    SessionView,
    TaskDraft,
    Template,
    TemplateUnfit,
    fmt_xy,
    tour_length,
)
from benchmark.scoring.validators import ENDPOINTS, leaf_count, parse_tree
from emulator.scenario import scenario_from_dict

TEMPLATES: tuple[Template, ...] = (*navigation.TEMPLATES, *delivery.TEMPLATES,
                                   *battery.TEMPLATES, *communication.TEMPLATES)
BY_KEY = {t.key: t for t in TEMPLATES}
SEEDS_PER_SESSION = 8  # x 15 sessions = 120 builds per template

KEYS = {
    "navigation": {"checkpoint", "waypoint_tour", "patrol_loop", "compass_legs",
                   "precision_landing", "long_survey", "dual_survey"},
    "delivery": {"parcel_delivery", "multi_drop", "team_delivery"},
    "battery_management": {"recharge_stop", "tour_then_recharge", "return_with_reserve"},
    "communication": {"relay_report", "broadcast_status", "spot_and_tell"},
}

OP_KEYS = {
    "takeoff": {"drone", "altitude_m"}, "goto": {"drone", "x", "y", "z"},
    "path": {"drone", "points"}, "land": {"drone"}, "hover": {"drone", "duration_s"},
    "towards": {"drone", "heading_deg", "distance_m"}, "home": {"drone", "altitude_m"},
    "charge": {"drone", "station"}, "message": {"drone", "to", "text"},
    "broadcast": {"drone", "text"}, "reach": {"drone", "target", "altitude_m"},
}

FLOAT_PARAMS = {"x", "y", "z", "tolerance", "min_distance", "max_distance", "heading",
                "min_level", "min_altitude", "max_altitude"}  # ids are strings, counts ints
ID_PARAMS = {"drone_id", "drone_1_id", "drone_2_id", "to_drone_id"}


# ------------------------------------------------------------------ fixtures and helpers
@functools.cache
def session_view(family: str, level: str) -> SessionView:
    world = generate_world(family, level, 1)
    w, h = world["map_size_m"]
    return SessionView(family, scenario_from_dict(world, source=world["id"]), float(w),
                       float(h))


def views() -> Iterator[SessionView]:
    for family in FAMILIES:
        for level in LEVELS:
            yield session_view(family, level)


def level_of(view: SessionView) -> str:
    return next(lv for lv in LEVELS if session_view(view.family, lv) is view)


def _rng(key: str, view: SessionView, seed: int) -> random.Random:
    return random.Random(f"{key}/{view.family}/{view.map_w_m:.0f}/{seed}")


@functools.cache
def drafts(key: str) -> tuple[tuple[SessionView, int, TaskDraft], ...]:
    """Every successful build of a template over all sessions it fits."""
    template = BY_KEY[key]
    built = []
    for view in views():
        if not template.fits(view):
            continue
        for seed in range(SEEDS_PER_SESSION):
            with contextlib.suppress(TemplateUnfit):
                built.append((view, seed, template.build(view, _rng(key, view, seed))))
    return tuple(built)


def leaves(node: dict[str, Any]) -> Iterator[dict[str, Any]]:
    if "endpoint" in node:
        yield node
    else:
        for child in node["checks"]:
            yield from leaves(child)


def ops(draft: TaskDraft) -> Iterator[dict[str, Any]]:
    for phase in draft.oracle:
        yield from phase


def number_pattern(value: float, unit: bool = False) -> re.Pattern[str]:
    text = f"{value:.0f}"
    suffix = r" (m|metres)\b" if unit else r"(?![\d.]\d)"
    return re.compile(rf"(?<![\d.]){text}{suffix}")


def stated_facts(draft: TaskDraft, view: SessionView) -> list[str | re.Pattern[str]]:
    """What every phrasing must state for the checks of this draft."""
    names = {d.id: d.name for d in view.drones}
    targets = {t.id: t.name for t in view.scenario.world.targets}
    facts: list[str | re.Pattern[str]] = []
    for node in leaves(draft.checks):
        p, endpoint = node["parameters"], node["endpoint"]
        facts.extend(names[p[k]] for k in ID_PARAMS if k in p)
        if "target_id" in p:
            facts.append(targets[p["target_id"]])
        if "x" in p:
            facts.append(fmt_xy(p["x"], p["y"]))
        if p.get("z"):
            facts.append(number_pattern(p["z"], unit=True))
        if "content" in p:
            facts.append(p["content"])
        if endpoint == "drone_has_taken_off":
            facts.append(number_pattern(p["min_altitude"], unit=True))
        if endpoint == "drone_battery_level" and p["min_level"] < 99.0:
            facts.append(number_pattern(p["min_level"]))
        if endpoint == "drone_has_sent_message":
            facts.append(number_pattern(p["min_count"]))
        if endpoint == "drone_has_moved_directed_distance":
            facts.append(number_pattern(round(p["min_distance"] / 0.9), unit=True))
        if endpoint == "two_drones_distance":
            facts.append(number_pattern(p["min_distance"], unit=True))
    return facts


def plan_points(draft: TaskDraft) -> list[tuple[str, tuple[float, float, float]]]:
    """(drone, point) for every goto and path point of the oracle plan."""
    out = []
    for op in ops(draft):
        if op["op"] == "goto":
            out.append((op["drone"], (op["x"], op["y"], op["z"])))
        elif op["op"] == "path":
            out.extend((op["drone"], tuple(p)) for p in op["points"])
    return out


@functools.cache
def obstacle_union(family: str, level: str) -> shapely.Geometry:
    view = session_view(family, level)
    return shapely.union_all([o.footprint for o in view.scenario.world.obstacles])


def routes_m(draft: TaskDraft, view: SessionView) -> dict[str, float]:
    """Straight-line length of each drone's plan, from its home through every place it goes."""
    world = view.scenario.world
    here = {d.id: d.home_m[:2] for d in view.drones}
    length = dict.fromkeys(here, 0.0)
    for op in ops(draft):
        d: str = op["drone"]
        stops: list[tuple[float, float]] = []
        if op["op"] == "goto":
            stops = [(op["x"], op["y"])]
        elif op["op"] == "path":
            stops = [(p[0], p[1]) for p in op["points"]]
        elif op["op"] in ("charge", "reach"):
            target = world.target(op.get("station") or op["target"])
            stops = [target.position_m[:2]]
        elif op["op"] == "home":
            stops = [next(v.home_m[:2] for v in view.drones if v.id == d)]
        elif op["op"] == "towards":
            h = math.radians(op["heading_deg"])
            x, y = here[d]
            stops = [(x + op["distance_m"] * math.sin(h), y + op["distance_m"] * math.cos(h))]
        for stop in stops:
            length[d] += math.dist(here[d], stop)
            here[d] = stop
    return length


def handmade_view(drones: int, stations: int) -> SessionView:
    """A small hand-made session without targets: one wall, drones and stations."""
    data: dict[str, Any] = {
        "name": "handmade", "task_type": "others",
        "drones": [{"id": f"d{k}", "name": f"Drone {k}", "max_speed": 15, "max_altitude": 120,
                    "battery_capacity": 5000.0,
                    "position": {"x": 40.0 + 10 * k, "y": 40.0, "z": 0.0}}
                   for k in range(1, drones + 1)],
        "targets": [{"id": f"s{k}", "name": f"Charging Station {k}", "type": "waypoint",
                     "position": {"x": 450.0, "y": 100.0 * k, "z": 0.0}, "radius": 10}
                    for k in range(1, stations + 1)],
        "obstacles": [{"id": "o1", "name": "Wall", "type": "circle",
                       "position": {"x": 300.0, "y": 300.0, "z": 0.0}, "radius": 30,
                       "height": 0.0}],
    }
    return SessionView("target_assignment", scenario_from_dict(data), 600.0, 600.0)


# ------------------------------------------------------------------ the catalogue
def test_keys_categories_and_needs() -> None:
    by_category: dict[str, set[str]] = {}
    for t in TEMPLATES:
        assert t.category in CATEGORIES
        assert t.difficulty in ("easy", "medium", "hard")
        by_category.setdefault(t.category, set()).add(t.key)
    assert by_category == KEYS
    assert len(BY_KEY) == len(TEMPLATES)
    assert all(t.stations >= 1 for t in battery.TEMPLATES)
    assert all(t.drones >= 2 for t in communication.TEMPLATES)
    assert BY_KEY["dual_survey"].drones == BY_KEY["team_delivery"].drones == 2


def test_needs_follow_the_session() -> None:
    lone = handmade_view(drones=1, stations=0)
    fitting = {t.key for t in TEMPLATES if t.fits(lone)}
    assert fitting == {"checkpoint", "waypoint_tour", "patrol_loop", "compass_legs",
                       "precision_landing", "long_survey", "parcel_delivery", "multi_drop"}
    pair = handmade_view(drones=2, stations=1)
    assert all(t.fits(pair) for t in TEMPLATES)
    with pytest.raises(TemplateUnfit, match="no point or area target"):
        BY_KEY["spot_and_tell"].build(pair, random.Random(1))
    draft = BY_KEY["recharge_stop"].build(pair, random.Random(1))
    [[charge]] = draft.oracle
    assert charge["op"] == "charge" and charge["station"] == "s1"


# ------------------------------------------------------------------ every template
@pytest.mark.parametrize("key", sorted(BY_KEY))
@pytest.mark.slow
def test_builds_on_every_fitting_session(key: str) -> None:
    template = BY_KEY[key]
    fitting = [v for v in views() if template.fits(v)]
    assert len(fitting) == len(FAMILIES) * len(LEVELS)
    built = drafts(key)
    assert len(built) >= 0.95 * SEEDS_PER_SESSION * len(fitting)
    for view in fitting:  # every session gets at least some builds
        assert any(v is view for v, _, _ in built)


@pytest.mark.parametrize("key", sorted(BY_KEY))
def test_phrasings_state_every_checked_fact(key: str) -> None:
    for view, seed, draft in drafts(key):
        texts = draft.phrasings
        assert len(texts) == 3 and len(set(texts)) == 3, (seed, texts)
        for text in texts:
            assert text.strip() == text and len(text) > 30
            assert "_" not in text and "{" not in text, text
            assert not any(e in text for e in ENDPOINTS)
            for fact in stated_facts(draft, view):
                if isinstance(fact, str):
                    assert fact in text, (key, seed, fact, text)
                else:
                    assert fact.search(text), (key, seed, fact.pattern, text)


@pytest.mark.parametrize("key", sorted(BY_KEY))
def test_checks_are_well_formed(key: str) -> None:
    for view, _, draft in drafts(key):
        drone_ids = {d.id for d in view.drones}
        target_ids = {t.id for t in view.scenario.world.targets}
        found = list(leaves(draft.checks))
        assert 1 <= len(found) <= 25
        assert draft.checks["logic"] == "and"
        for node in found:
            p = node["parameters"]
            for name, value in p.items():
                if name in FLOAT_PARAMS:
                    assert type(value) is float, (name, value)
                if name in ID_PARAMS:
                    assert value in drone_ids
                if name == "target_id":
                    assert value in target_ids
            if "z" in p:
                assert p["z"] == 0.0 or 10.0 <= p["z"] <= 40.0
            if "tolerance" in p and "x" in p:
                assert p["tolerance"] == 3.0
        assert leaf_count(parse_tree(draft.checks, view.scenario)) == len(found)


@pytest.mark.parametrize("key", sorted(BY_KEY))
def test_oracle_plan_uses_known_ops_and_ids(key: str) -> None:
    for view, _, draft in drafts(key):
        drone_ids = {d.id for d in view.drones}
        stations = {t.id for t in view.stations}
        targets = {t.id for t in (*view.points, *view.areas)}
        assert draft.oracle and all(draft.oracle)
        for op in ops(draft):
            assert set(op) - {"op"} == OP_KEYS[op["op"]], op
            assert op["drone"] in drone_ids
            if op["op"] == "charge":
                assert op["station"] in stations
            if op["op"] == "reach":
                assert op["target"] in targets
            if op["op"] == "message":
                assert op["to"] in drone_ids and op["to"] != op["drone"]
            if op["op"] == "hover":
                assert 5 <= op["duration_s"] <= 20
            for name in ("altitude_m", "z"):
                if name in op:
                    assert 10 <= op[name] <= 40
        assert draft.flight_m >= 0.0 and draft.hover_s >= 0.0 and draft.steps >= 1
        used = {op["drone"] for op in ops(draft)}
        checked = {n["parameters"][k] for n in leaves(draft.checks) for k in ID_PARAMS
                   if k in n["parameters"]}
        assert checked <= used | {op["to"] for op in ops(draft) if op["op"] == "message"}


@pytest.mark.parametrize("key", sorted(BY_KEY))
def test_points_to_visit_are_free_and_inside_the_map(key: str) -> None:
    for view, seed, draft in drafts(key):
        blocked = obstacle_union(view.family, level_of(view))
        for _, (x, y, _z) in plan_points(draft):
            assert 20.0 <= x <= view.map_w_m - 20.0 and 20.0 <= y <= view.map_h_m - 20.0
            assert blocked.distance(shapely.Point(x, y)) >= 15.0, (key, seed, x, y)


@pytest.mark.parametrize("key", sorted(BY_KEY))
def test_routes_fit_one_battery(key: str) -> None:
    for view, seed, draft in drafts(key):
        longest = max(routes_m(draft, view).values())
        assert longest <= 4000.0, (key, seed, longest)
        assert draft.flight_m >= 0.8 * longest - 1.0 or draft.flight_m == 0.0


@pytest.mark.parametrize("key", sorted(BY_KEY))
def test_same_seed_same_draft(key: str) -> None:
    template = BY_KEY[key]
    for view in (session_view("area_search", "easy"), session_view("target_assignment",
                                                                   "extreme")):
        first = template.build(view, _rng(key, view, 99))
        assert template.build(view, _rng(key, view, 99)) == first
        others = [template.build(view, _rng(key, view, s)) for s in range(3)]
        assert any(o.checks != first.checks for o in others)


# ------------------------------------------------------------------ template specifics
def test_patrol_loop_is_a_closed_rectangle() -> None:
    for _, _, draft in drafts("patrol_loop"):
        visited = [(n["parameters"]["x"], n["parameters"]["y"]) for n in leaves(draft.checks)
                   if n["endpoint"] == "drone_has_visited_position"]
        xs, ys = sorted({x for x, _ in visited}), sorted({y for _, y in visited})
        assert len(visited) == 4 and len(xs) == len(ys) == 2
        assert xs[1] - xs[0] >= 150.0 and ys[1] - ys[0] >= 150.0
        perimeter = 2 * (xs[1] - xs[0] + ys[1] - ys[0])
        (moved,) = [n for n in leaves(draft.checks) if n["endpoint"] == "drone_has_moved_distance"]
        assert moved["parameters"]["min_distance"] == round(0.9 * perimeter)
        (end,) = [n for n in leaves(draft.checks) if n["endpoint"] == "drone_position"]
        assert (end["parameters"]["x"], end["parameters"]["y"]) == visited[0]
        route = [p[:2] for _, p in plan_points(draft)]
        assert route == [*visited, visited[0]]
        for a, b in itertools.pairwise(route):  # sides run along the axes
            assert a[0] == b[0] or a[1] == b[1]


def test_compass_legs_are_clear_and_sized() -> None:
    for view, seed, draft in drafts("compass_legs"):
        (goto, north, east) = draft.oracle[0]
        assert (north["heading_deg"], east["heading_deg"]) == (0.0, 90.0)
        assert 60 <= north["distance_m"] <= 150 and 60 <= east["distance_m"] <= 150
        start = (goto["x"], goto["y"])
        turn = (start[0], start[1] + north["distance_m"])
        end = (turn[0] + east["distance_m"], turn[1])
        assert view.clear_leg(start, turn, goto["z"]), seed
        assert view.clear_leg(turn, end, goto["z"]), seed
        assert end[0] <= view.map_w_m - 30.0 and end[1] <= view.map_h_m - 30.0
        mins = sorted((n["parameters"]["heading"], n["parameters"]["min_distance"])
                      for n in leaves(draft.checks)
                      if n["endpoint"] == "drone_has_moved_directed_distance")
        assert mins == [(0.0, round(0.9 * north["distance_m"], 1)),
                        (90.0, round(0.9 * east["distance_m"], 1))]


def test_surveys_have_their_sizes_and_end_on_the_ground() -> None:
    for key, drones, sizes in (("long_survey", 1, range(8, 13)),
                               ("dual_survey", 2, range(5, 7)),
                               ("waypoint_tour", 1, range(4, 6))):
        for _, _, draft in drafts(key):
            per_drone: dict[str, int] = {}
            for n in leaves(draft.checks):
                if n["endpoint"] == "drone_has_visited_position":
                    d = n["parameters"]["drone_id"]
                    per_drone[d] = per_drone.get(d, 0) + 1
            assert len(per_drone) == drones
            assert all(count in sizes for count in per_drone.values())
            lands = [op for op in ops(draft) if op["op"] == "land"]
            assert len(lands) == (drones if key != "waypoint_tour" else 0)
            if key == "dual_survey":
                alts = {op["z"] for op in ops(draft) if op["op"] == "goto"}
                assert len(alts) == 2


def test_deliveries_are_landings() -> None:
    for key, landings in (("parcel_delivery", 2), ("multi_drop", 3), ("team_delivery", 2)):
        for _, _, draft in drafts(key):
            visits = [n["parameters"] for n in leaves(draft.checks)
                      if n["endpoint"] == "drone_has_visited_position"]
            assert visits and all(v["z"] == 0.0 for v in visits)
            landed = [n["parameters"]["min_count"] for n in leaves(draft.checks)
                      if n["endpoint"] == "drone_has_landed"]
            assert landed and all(c == landings for c in landed)
            spots = [(v["x"], v["y"]) for v in visits]
            assert min(math.dist(a, b) for a in spots for b in spots if a != b) >= 60.0
            for op in ops(draft):  # every goto is followed by a landing
                if op["op"] == "goto":
                    phase = next(p for p in draft.oracle if op in p)
                    mine = [o for o in phase if o["drone"] == op["drone"]]
                    assert mine[mine.index(op) + 1]["op"] == "land"
    for _, _, draft in drafts("team_delivery"):
        (apart,) = [n for n in leaves(draft.checks) if n["endpoint"] == "two_drones_distance"]
        ends = [(n["parameters"]["x"], n["parameters"]["y"]) for n in leaves(draft.checks)
                if n["endpoint"] == "drone_position"]
        assert apart["parameters"]["min_distance"] == 30.0
        assert math.dist(*ends) >= 100.0


def test_battery_tasks_end_on_a_station_or_at_home() -> None:
    for key in ("recharge_stop", "tour_then_recharge"):
        for view, _, draft in drafts(key):
            (inside,) = [n for n in leaves(draft.checks) if n["endpoint"] == "drone_in_target"]
            station = view.scenario.world.target(inside["parameters"]["target_id"])
            assert station.is_charging_station
            assert draft.oracle[0][-1] == {"op": "charge", "drone": inside["parameters"][
                "drone_id"], "station": station.id}
            assert draft.hover_s > 30.0
    for view, _, draft in drafts("return_with_reserve"):
        d = draft.oracle[0][0]["drone"]
        home = next(v.home_m[:2] for v in view.drones if v.id == d)
        points = [p[:2] for _, p in plan_points(draft)]
        assert len(points) == 3
        assert tour_length([home, *points, home]) <= battery.MAX_RESERVE_TOUR_M
        (level,) = [n for n in leaves(draft.checks) if n["endpoint"] == "drone_battery_level"]
        assert level["parameters"]["min_level"] == 50.0


def test_messages_carry_the_checked_words() -> None:
    code_word = re.compile(rf"^({'|'.join(communication.CODE_WORDS)})-\d{{1,2}}$")
    for key in ("relay_report", "spot_and_tell"):
        for _, _, draft in drafts(key):
            (sent,) = [n["parameters"] for n in leaves(draft.checks)
                       if n["endpoint"] == "drone_has_sent_message_content"]
            (message,) = [op for op in ops(draft) if op["op"] == "message"]
            assert sent["content"] in message["text"]
            assert (sent["drone_id"], sent["to_drone_id"]) == (message["drone"], message["to"])
            if key == "relay_report":
                assert code_word.match(sent["content"])
    for _, _, draft in drafts("spot_and_tell"):
        phases = [[op["op"] for op in phase] for phase in draft.oracle]
        assert phases == [["reach"], ["message"], ["reach"]]
    for _, _, draft in drafts("broadcast_status"):
        (count,) = [n["parameters"]["min_count"] for n in leaves(draft.checks)
                    if n["endpoint"] == "drone_has_sent_message"]
        assert count in (2, 3)
        assert sum(op["op"] == "broadcast" for op in ops(draft)) == count
