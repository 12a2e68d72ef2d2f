"""Template files: the format's round trip, its schema, its errors, the placeholder grammar
(ours and the reference's, case by case) and the built-in templates written as files."""

from __future__ import annotations

import functools
import json
import random
import re
from pathlib import Path
from typing import Any

import jsonschema
import pytest

from benchmark.authoring.generate import build_task
from benchmark.authoring.scenarios import FAMILIES, LEVELS, generate_world
from benchmark.authoring.session_file import session_from_dict, task_from_dict
from benchmark.authoring.template_files import (
    SCHEMA_PATH,
    TemplateFile,
    TemplateFileError,
    dump_template,
    json_schema,
    load_template,
    load_templates,
    read_template,
    schema_text,
    template_of,
)
from benchmark.authoring.template_files.model import CATEGORIES as FILE_CATEGORIES
from benchmark.authoring.template_files.placeholders import Filler
from benchmark.authoring.templates import CATALOGUE, basic
from benchmark.authoring.templates.base import CATEGORIES, SessionView

FILES = sorted(basic.FILES.glob("*.json"))


@functools.cache
def view(family: str = "area_search", level: str = "hard") -> SessionView:
    world = generate_world(family, level, 1)
    session = session_from_dict({**world, "tasks": []})
    w, h = world["map_size_m"]
    return SessionView(family, session.scenario, float(w), float(h))


def _write(tmp_path: Path, data: dict[str, Any], name: str = "t.json") -> Path:
    path = tmp_path / name
    path.write_text(json.dumps(data), encoding="utf-8")
    return path


def _minimal(**extra: Any) -> dict[str, Any]:
    return {"format": "mavswarm.template/1", "id": "hover_here", "category": "navigation",
            "entities": [{"group": "drone_1", "kind": "drone"}],
            "values": [{"name": "alt", "kind": "int", "min": 10, "max": 20}],
            "phrasings": ["Hover {drone_1_name} at {alt} m."],
            "checks": {"logic": "and", "checks": [
                {"endpoint": "drone_altitude", "parameters": {
                    "drone_id": "{drone_1_id}", "expected_altitude": "{alt}"}}]}} | extra


# ------------------------------------------------------------------ the format
@pytest.mark.parametrize("path", FILES, ids=lambda p: p.stem)
def test_file_model_file_round_trip(path: Path, tmp_path: Path) -> None:
    model = read_template(path)
    again = read_template(_write(tmp_path, json.loads(dump_template(model))))
    assert again == model
    assert dump_template(again) == dump_template(model)


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.stem)
def test_every_shipped_file_meets_the_published_schema(path: Path) -> None:
    jsonschema.validate(json.loads(path.read_text()), json_schema())


def test_the_published_schema_is_generated_from_the_model() -> None:
    assert SCHEMA_PATH.read_text(encoding="utf-8") == schema_text()
    assert FILE_CATEGORIES == CATEGORIES


@pytest.mark.parametrize(("change", "field", "reason"), [
    ({"category": "juggling"}, "category", "is not one of basic_operations"),
    ({"id": "Bad Id"}, "id", "should match pattern"),
    ({"phrasings": []}, "phrasings", "at least 1 item"),
    ({"values": [{"name": "alt", "kind": "int", "min": 9}]}, "values[0]", "needs min and max"),
    ({"values": [{"name": "alt", "kind": "int", "min": 9, "max": 3}]}, "values[0]",
     "max 3 < min 9"),
    ({"entities": [{"group": "Pilot-1", "kind": "drone"}]}, "entities[0].group",
     "should match pattern"),
    ({"families": ["skiing"]}, "families", "'skiing' is not one of"),
    ({"levels": ["easy", "insane"]}, "levels", "'insane' is not one of"),
    ({"colour": "red"}, "colour", "Extra inputs are not permitted"),
    ({"checks": {"endpoint": "drone_flies", "parameters": {}}}, "checks",
     "unknown endpoint 'drone_flies'"),
])
def test_errors_name_the_file_the_field_and_the_reason(tmp_path: Path, change: dict[str, Any],
                                                       field: str, reason: str) -> None:
    path = _write(tmp_path, _minimal(**change))
    with pytest.raises(TemplateFileError) as caught:
        read_template(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: {field}"), message
    assert reason in message


def test_unreadable_files_and_duplicate_ids_are_refused(tmp_path: Path) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text("{not json", encoding="utf-8")
    with pytest.raises(TemplateFileError, match=r"bad\.json: not JSON"):
        read_template(bad)
    bad.unlink()
    _write(tmp_path, _minimal(), "a.json")
    _write(tmp_path, _minimal(), "b.json")
    with pytest.raises(TemplateFileError, match=r"b\.json: id: 'hover_here' is also the id of"):
        load_templates(tmp_path)


def test_a_file_template_builds_tasks_that_session_files_accept(tmp_path: Path) -> None:
    template = template_of(TemplateFile.model_validate(_minimal()))
    task = build_task(template, view(), random.Random(3), "t01")
    assert task["oracle"] is None  # no hand plan: the derived planner proves it
    leaf = task["checks"]["checks"][0]["parameters"]
    assert isinstance(leaf["expected_altitude"], float)
    assert leaf["drone_id"] in {d.id for d in view().drones}
    assert task_from_dict(0, task, view().scenario).error is None
    assert re.fullmatch(r"Hover Drone \d+ at \d+ m\.", task["text"])


# ------------------------------------------------------------------ built-ins as files
def test_the_shipped_files_are_in_the_catalogue() -> None:
    keys = [t.key for t in CATALOGUE if t.category == "basic_operations"]
    assert keys == list(basic.KEYS)
    by_key = {t.key: t for t in CATALOGUE}
    for template in load_templates(basic.FILES):
        entry = by_key[template.key]
        assert (entry.category, entry.difficulty, entry.drones, entry.families) == (
            template.category, template.difficulty, template.drones, template.families)
    assert {p.stem for p in FILES} >= set(basic.KEYS) | {
        "checkpoint", "precision_landing", "photo_at_point", "relay_report"}
    files = {t.key for t in load_templates(basic.FILES)}
    assert {t.category for t in CATALOGUE if t.key in files} == set(CATEGORIES)


# ------------------------------------------------------------------ placeholders
def _filler(seed: int = 1, **values: Any) -> Filler:
    return Filler(random.Random(seed), view(), {"drone_1_id": "d2", "drone_1_name": "Drone 2"},
                  values)


def test_entities_and_named_values() -> None:
    f = _filler(alt=12, p=(101.0, 202.0))
    assert f.text("{drone_1_name} to {p} at {alt} m ({p.x}/{p.y})") == (
        "Drone 2 to (101, 202) at 12 m (101/202)")
    assert f.structure({"drone_id": "{drone_1_id}", "z": "{alt}", "x": "{p.x}"}, plan=False) == {
        "drone_id": "d2", "z": 12.0, "x": 101.0}
    plan = f.structure([{"op": "takeoff", "altitude_m": "{alt}"}], plan=True)
    assert plan == [{"op": "takeoff", "altitude_m": 12}] and isinstance(
        plan[0]["altitude_m"], int)


def test_sticky_named_randoms_keep_their_first_value_whatever_range_later() -> None:
    f = _filler()
    first = f.text("{random_alt:10:20}")
    assert f.text("{random_alt:500:900} {random_alt}") == f"{first} {first}"
    assert 10 <= int(first) <= 20
    n = f.text("{randint_count:3:5}")
    assert f.text("{randint_count}") == n and 3 <= int(n) <= 5
    assert f.text("{random_speed2:1:2:2}").count(".") == 1  # two decimals
    assert f.structure({"min_count": "{randint_count}"}, plan=False) == {"min_count": float(n)}


def test_a_reference_to_a_value_not_drawn_is_left_as_written() -> None:
    assert _filler().text("{randint_never} {drone_4_name}") == "{randint_never} {drone_4_name}"


def test_anonymous_randoms_draw_anew_and_predefined_ones_stick() -> None:
    f = _filler(seed=7)
    draws = {f.text("{randint:1:1000}") for _ in range(20)}
    assert len(draws) > 10 and all(1 <= int(v) <= 1000 for v in draws)
    value = f.text("{random:0:1:3}")
    assert re.fullmatch(r"0\.\d{3}|1\.000", value)
    alt = f.text("{random_altitude}")
    assert f.text("{random_altitude}") == alt and 5 <= int(alt) <= 100


def test_named_positions_are_drawn_together_and_avoid_obstacles() -> None:
    v = view("area_search", "extreme")
    blocked = [o.footprint.buffer(1.0) for o in v.scenario.world.obstacles]
    assert blocked
    for seed in range(40):
        f = Filler(random.Random(seed), v, {}, {})
        text = f.text("go to ({randx_wp:0:600}, {randy_wp:0:600}) at {randz_wp:15:20}")
        x, y, z = (float(s) for s in re.findall(r"-?\d+(?:\.\d+)?", text))
        assert 15 <= z <= 20
        import shapely
        assert not any(b.contains(shapely.Point(x, y)) for b in blocked), (seed, x, y)
        assert f.text("{randx_wp},{randy_wp}") == f"{x:.0f},{y:.0f}"


def test_composites_come_first_and_give_their_components() -> None:
    f = _filler(seed=3)
    xy = f.text("{randxyc_base:100:300}")
    x, y = xy.split(", ")
    assert f.text("{randx_base} {randy_base}") == f"{x} {y}"
    assert len(f.text("{randpos_top}").split(", ")) == 3
    assert len(f.text("{randxyz}").split(" ")) == 3


def test_the_last_occurrence_sets_a_coordinated_range() -> None:
    for seed in range(30):  # the reference's quirk: the unranged last z spans [0, 100]
        f = _filler(seed=seed)
        f.text("{randz_c:15:20} ({randx_c:350:600}, {randy_c:350:600}, {randz_c})")
        assert 0.0 <= f.cache["randz_c"] <= 100.0
    zs = []
    for seed in range(30):
        f = _filler(seed=seed)
        f.text("({randx_c:350:600}, {randy_c:350:600}, {randz_c:15:20})")
        zs.append(f.cache["randz_c"])
    assert all(15 <= z <= 20 for z in zs)


def test_z_ranges_are_capped_at_100_and_expect_words_become_booleans() -> None:
    f = _filler()
    assert 0 <= int(f.text("{randz:150:300}")) <= 100
    leaf = {"endpoint": "drone_on_ground", "parameters": {}, "expect": "false"}
    assert f.structure(leaf, plan=False)["expect"] is False
    assert "expect" not in f.structure({**leaf, "expect": "maybe"}, plan=False)
    assert _filler().text("Drone {drone_1_name}") == "Drone 2"


def test_a_reference_style_template_generates_tasks(tmp_path: Path) -> None:
    data = {"format": "mavswarm.template/1", "id": "quick_checkpoint",
            "category": "navigation", "entities": [{"group": "drone", "kind": "drone"}],
            "phrasings": ["Fly {drone_name} to ({randx_cp:100:500}, {randy_cp:100:500}) at "
                          "{randz_cp:12:18} m."],
            "checks": [{"endpoint": "drone_has_visited_position", "parameters": {
                "drone_id": "{drone_id}", "x": "{randx_cp}", "y": "{randy_cp}",
                "z": "{randz_cp}", "tolerance": 3.0}}]}
    template = template_of(read_template(_write(tmp_path, data)))
    task = build_task(template, view(), random.Random(11), "t01")
    x, y, z = (float(v) for v in re.findall(r"\d+", task["text"])[1:4])
    params = task["checks"][0]["parameters"]
    assert (params["x"], params["y"], params["z"]) == (x, y, z)
    assert task_from_dict(0, task, view().scenario).error is None


@pytest.mark.parametrize("family", FAMILIES)
def test_file_templates_fit_the_families_they_name(family: str) -> None:
    v = view(family, LEVELS[0])
    for template in load_templates(basic.FILES):
        needs = template.area_targets + template.moving_targets + template.point_targets
        if not template.families and not needs and not template.stations:
            assert template.fits(v), template.key
        if template.families:
            assert template.fits(v) == (family in template.families), template.key


def test_hooks_entity_positions_faults_and_keys_are_filled(tmp_path: Path) -> None:
    data = _minimal(
        entities=[{"group": "drone_1", "kind": "drone"}, {"group": "spot", "kind": "inspectable"}],
        values=[{"name": "alt", "kind": "int", "min": 10, "max": 20},
                {"name": "extra", "kind": "hook",
                 "call": "benchmark.authoring.templates.resilience:lossy_delivery"}],
        phrasings=["{drone_1_name} from {drone_1_xy} to {spot_name} at {spot_xy}, then {drop}."],
        faults={"link": {"seed": "{link_seed}", "vehicles": {"{drone_1_id}": {
            "uplink": {"loss": 0.1}}}}})
    template = template_of(read_template(_write(tmp_path, data)))
    task = build_task(template, view(), random.Random(5), "t01")
    vehicles = task["faults"]["link"]["vehicles"]
    drone = next(iter(vehicles))
    assert drone in {d.id for d in view().drones}
    assert isinstance(task["faults"]["link"]["seed"], int)
    assert re.fullmatch(r"Drone \d+ from \(\d+, \d+\) to .+ at \(\d+, \d+\), then "
                        r"\(\d+, \d+\)\.", task["text"]), task["text"]
    bad = _minimal(values=[{"name": "x", "kind": "hook", "call": "nowhere.at_all:f"}])
    path = _write(tmp_path, bad, "bad_hook.json")
    with pytest.raises(TemplateFileError, match=r"bad_hook\.json: values\[0\]\.call: hook "
                                                r"'nowhere.at_all:f' cannot be loaded"):
        load_template(path)
