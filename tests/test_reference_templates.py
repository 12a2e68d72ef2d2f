"""MultiUAV-Plat template files read as they are (one template, or a catalogue keyed by
template), case by case; round trips reference file -> tasks -> our file -> the same tasks;
generation and import proving every task with the oracle; --drones and --map-size-m."""

from __future__ import annotations

import copy
import json
import random
import subprocess
from pathlib import Path
from typing import Any

import pytest

from benchmark.authoring.generate import build_task
from benchmark.authoring.scenarios import generate_world
from benchmark.authoring.session_file import dump_session, load_session, session_from_dict
from benchmark.authoring.template_files import (
    TemplateFileError,
    dump_template,
    load_templates,
    read_template,
    read_templates,
    template_of,
)
from benchmark.authoring.templates.base import SessionView
from benchmark.authoring.templates.common import FILES
from benchmark.running.generation import generate_session
from tests.bench_fixtures import reference_session
from tests.cli_fixtures import run_in_process

ROOT = Path(__file__).resolve().parent.parent
DEFAULTS = ROOT / "tests" / "data" / "multiuav_default_templates.json"


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    """`mavswarm ARGS` by the command's `main` in this process (what it prints and its status
    are what is checked; the command as a process is tested in test_cli_errors.py)."""
    return run_in_process(*args, cwd=ROOT)


def _view(family: str = "area_search", level: str = "moderate", **sized: Any) -> SessionView:
    world = generate_world(family, level, 1, **sized)
    session = session_from_dict({**world, "tasks": []})
    w, h = world["map_size_m"]
    return SessionView(family, session.scenario, float(w), float(h))


def _ref(**extra: Any) -> dict[str, Any]:
    """One template in the reference's layout."""
    return {"name": "Quick Check", "description": "", "creator": "Lab",
            "content": "Drone {drone_name}: fly to ({randx_q:350:600}, {randy_q:350:600}) at "
                       "{randz_q:12:18} m. ({name} by {creator})",
            "content_aliases": ["{drone_name} goes to ({randx_q:350:600}, {randy_q:350:600})."],
            "difficulty": "easy", "category": "Navigation", "is_builtin": False,
            "exclude_in_random_generation": False, "suitable_task": ["all"],
            "related_apis": [{"endpoint": "/drones/{id}/command/take_off",
                              "parameters": {"id": "{drone_id}", "altitude": "{randz_q}"}}],
            "execution_check_apis": {"logic": "and", "checks": [
                {"endpoint": "/check/drone_has_visited_position", "parameters": {
                    "drone_id": "{drone_id}", "x": "{randx_q}", "y": "{randy_q}",
                    "z": "{randz_q}", "tolerance": 3.0}},
                {"endpoint": "/check/drone_has_landed",
                 "parameters": {"drone_id": "{drone_id}", "max_altitude": 1.0}},
                {"endpoint": "/check/drone_on_ground",
                 "parameters": {"drone_id": "{drone_id}"}, "expect": "false"}]},
            "commands": ["take_off", "move_to"], "created_at": 1.0} | extra


def _write(path: Path, data: Any) -> Path:
    path.write_text(json.dumps(data), encoding="utf-8")
    return path


# ------------------------------------------------------------------ the layout, case by case
def test_the_default_catalogue_is_read_as_it_is() -> None:
    raw = json.loads(DEFAULTS.read_text())
    models = read_templates(DEFAULTS)
    kept = [k for k, v in raw.items() if not v["exclude_in_random_generation"]]
    assert [m.id for m in models] == kept and len(kept) == 53 and len(raw) == 58
    by_id = {m.id: m for m in models}
    assert by_id["adaptive_search_and_track"].category == "target_tracking"
    assert by_id["coordinated_search_sweep"].category == "multi_drone_coordination"
    assert by_id["area_coverage_search"].families == ["area_search",
                                                      "area_assignment_and_patrol"]
    assert by_id["basic_takeoff"].families == []  # "all"
    groups = [(g.group, g.kind) for g in by_id["multiple_target_inspection_advanced"].entities]
    assert groups == [(f"drone_{k}", "drone") for k in (1, 2, 3)] + [
        (f"target_{k}", "target") for k in range(1, 7)]
    assert [g.kind for g in by_id["complex_obstacle_course"].entities] == [
        "drone", "obstacle", "obstacle", "obstacle"]
    assert all(m.distinct == "when_enough" for m in models)
    leaves = by_id["complete_flight_cycle"].checks["checks"]
    assert [c["endpoint"] for c in leaves] == ["drone_has_taken_off",
                                               "drone_has_visited_position",
                                               "drone_has_landed", "drone_at_home"]
    assert leaves[1]["parameters"]["z"] == "{randz_cycle}"


def test_one_template_per_file_with_names_phrasings_and_typed_checks(tmp_path: Path) -> None:
    (model,) = read_templates(_write(tmp_path / "Quick Check.json", _ref()))
    assert model.id == "quick_check" and model.category == "navigation"
    assert model.difficulty == "easy" and len(model.phrasings) == 2
    task = build_task(template_of(model), _view(), random.Random(5), "t01")
    assert task["text"].startswith("Drone ") and "Drone Drone" not in task["text"]
    assert task["text"].endswith("(Quick Check by Lab)")
    visited, landed, ground = task["checks"]["checks"]
    x, y, z = (visited["parameters"][k] for k in "xyz")
    assert isinstance(x, float) and 350 <= x <= 600 and 12 <= z <= 18
    assert f"({x:.0f}, {y:.0f})" in task["text"] and f"({x:.0f}, {y:.0f})" in task["aliases"][0]
    assert landed["endpoint"] == "drone_has_landed"
    assert landed["parameters"]["drone_id"] == visited["parameters"]["drone_id"]
    assert ground["expect"] is False


@pytest.mark.parametrize(("change", "message"), [
    ({"content": ""}, "content: missing or empty"),
    ({"category": "Juggling"}, "category: 'Juggling' is not one of"),
    ({"execution_check_apis": {"logic": "and", "checks": []}}, "execution_check_apis: the "
                                                               "template has no checks"),
    ({"content_aliases": "one"}, "content_aliases: expected a list"),
    ({"execution_check_apis": {"checks": [{"endpoint": "/check/drone_is_happy",
                                           "parameters": {}}]}}, "drone_is_happy"),
])
def test_errors_name_the_file_the_key_and_the_field(tmp_path: Path, change: dict[str, Any],
                                                   message: str) -> None:
    path = _write(tmp_path / "cat.json", {"fine": _ref(), "broken": _ref(**change)})
    with pytest.raises(TemplateFileError) as caught:
        read_templates(path)
    assert str(caught.value).startswith(f"{path}: broken")
    assert message in str(caught.value)


def test_excluded_templates_are_left_out_and_suitability_is_normalised(tmp_path: Path) -> None:
    path = _write(tmp_path / "cat.json", {
        "a": _ref(suitable_task="target_assignment"),
        "b": _ref(suitable_task=["others", "area_search"]),
        "c": _ref(suitable_task=["target_tracking", "all"]),
        "d": _ref(suitable_task=[]),
        "skip": _ref(exclude_in_random_generation=True)})
    families = {m.id: m.families for m in read_templates(path)}
    assert families == {"a": ["target_assignment"], "b": ["area_search"], "c": [], "d": []}


def test_groups_are_distinct_when_the_session_has_enough_else_drawn_with_replacement() -> None:
    model = {m.id: m for m in read_templates(DEFAULTS)}[
        "fleet_coordination_takeoff_and_formation_5drones"]
    template = template_of(model)
    small, large = _view("area_search", "easy"), _view("area_search", "moderate")
    assert len(small.drones) == 3 and template.fits(small)
    for seed in range(5):
        ids = {c["parameters"]["drone_id"] for c in build_task(
            template, large, random.Random(seed), "t")["checks"]["checks"]}
        assert len(ids) == 5
        ids = {c["parameters"]["drone_id"] for c in build_task(
            template, small, random.Random(seed), "t")["checks"]["checks"]}
        assert ids <= {d.id for d in small.drones} and len(ids) <= 3


def test_reference_file_to_tasks_to_our_file_to_the_same_tasks(tmp_path: Path) -> None:
    view = _view("target_assignment", "moderate")
    for model in read_templates(DEFAULTS):
        template = template_of(model)
        if not template.fits(view):
            continue
        ours = tmp_path / f"{model.id}.json"
        ours.write_text(dump_template(model), encoding="utf-8")
        again = read_template(ours)
        assert again == model and dump_template(again) == ours.read_text()
        first = build_task(template, view, random.Random(model.id), "t01")
        second = build_task(template_of(again), view, random.Random(model.id), "t01")
        assert first == second, model.id
    world = generate_world("target_assignment", "moderate", 1)
    tasks = [build_task(template_of(m), view, random.Random(3), f"t{k:02d}")
             for k, m in enumerate(read_templates(DEFAULTS)[:6], start=1)]
    text = dump_session({**world, "tasks": tasks})
    path = tmp_path / "s.json"
    path.write_text(text)
    loaded = load_session(path)
    assert [t.error for t in loaded.tasks] == [None] * 6
    assert json.loads(text)["tasks"] == tasks


def test_a_folder_of_reference_files_beside_ours_loads_into_one_catalogue(tmp_path: Path
                                                                          ) -> None:
    _write(tmp_path / "lab.json", {"quick_check": _ref(), "other_check": _ref()})
    ours = read_template(FILES / "takeoff_hold.json")
    (tmp_path / "zz_ours.json").write_text(dump_template(ours))
    assert [t.key for t in load_templates(tmp_path)] == ["quick_check", "other_check",
                                                         "takeoff_hold"]
    _write(tmp_path / "again.json", _ref())  # a single template whose id is the file's stem
    _write(tmp_path / "quick_check.json", _ref())
    with pytest.raises(TemplateFileError, match="'quick_check' is also the id of"):
        load_templates(tmp_path)


# ------------------------------------------------------------------ proving
def test_generation_from_reference_templates_proves_every_task(tmp_path: Path) -> None:
    folder = tmp_path / "templates"
    folder.mkdir()
    raw = json.loads(DEFAULTS.read_text())
    _write(folder / "task_templates.json",
           {k: raw[k] for k in ("quick_checkpoint", "target_inspection")})
    result = _cli("bench", "generate", "--out", str(tmp_path / "out"), "--families",
                  "target_assignment", "--levels", "easy", "--sessions-per-cell", "1",
                  "--tasks-per-session", "3", "--templates", str(folder),
                  "--replace-templates")
    assert result.returncode == 0, result.stdout + result.stderr
    session = json.loads((tmp_path / "out" / "target_assignment-easy-1.json").read_text())
    assert {t["template"] for t in session["tasks"]} <= {"quick_checkpoint",
                                                          "target_inspection"}
    assert all(t["oracle"] is None for t in session["tasks"])


def test_import_proves_each_task_and_names_the_leaf_it_could_not_prove(tmp_path: Path
                                                                        ) -> None:
    data = reference_session()
    drone = data["drones"][0]["id"]
    good: dict[str, Any] = {"id": "aa11bb22", "name": "Climb", "content": "Climb to 12 m.",
            "execution_check_apis": {"logic": "and", "checks": [
                {"endpoint": "/check/drone_altitude", "parameters": {
                    "drone_id": drone, "expected_altitude": 12.0, "tolerance": 2.0}}]}}
    never = copy.deepcopy(good) | {"id": "cc33dd44", "content": "Fly 900 km."}
    never["execution_check_apis"]["checks"] = [
        {"endpoint": "/check/drone_has_moved_distance",
         "parameters": {"drone_id": drone, "min_distance": 900000}}]
    source = _write(tmp_path / "ref.json", {**data, "tasks": [good, never]})
    result = _cli("bench", "import", str(source), "--out", str(tmp_path / "out"))
    assert result.returncode == 1, result.stdout + result.stderr
    assert "cc33dd44 (imported:Climb): NOT proved: checks[0] drone_has_moved_distance" in (
        result.stdout)
    assert "oracle: 1 of 2 tasks proved" in result.stdout
    written = json.loads(next((tmp_path / "out").glob("*.json")).read_text())
    first, second = (t["proof"] for t in written["tasks"])
    assert first == {"by": "oracle", "proved": True}
    assert second["proved"] is False and second["leaf"] == "checks[0]"
    assert second["endpoint"] == "drone_has_moved_distance" and second["reason"]
    quick = _cli("bench", "import", str(source), "--out", str(tmp_path / "fast"),
                 "--no-prove")
    assert quick.returncode == 0 and "proof" not in json.loads(
        next((tmp_path / "fast").glob("*.json")).read_text())["tasks"][0]


# ------------------------------------------------------------------ drones and map size
def test_drones_and_map_size_shape_every_world_deterministically() -> None:
    world = generate_world("target_tracking", "easy", 2, drones=9, map_size_m=900)
    assert len(world["drones"]) == 9 and world["map_size_m"] == [900, 900]
    assert "900 x 900 m map with 9 drones" in world["description"]
    assert generate_world("target_tracking", "easy", 2, drones=9, map_size_m=900) == world
    plain = generate_world("target_tracking", "easy", 2)
    assert generate_world("target_tracking", "easy", 2, drones=0, map_size_m=0) == plain
    session = generate_session("area_search", "easy", 1, verify=False, tasks=4, drones=5,
                               map_size_m=700.0, progress=lambda _: None)
    assert len(session["drones"]) == 5 and session["map_size_m"] == [700, 700]
    assert all(0 <= d["position"]["x"] <= 700 for d in session["drones"])
    for bad, message in (({"drones": 101}, "--drones must be a whole number from 1 to 100"),
                         ({"map_size_m": 150.0}, "--map-size-m must be from 200")):
        with pytest.raises(ValueError, match=message):
            generate_world("area_search", "easy", 1, **bad)


def test_generate_cli_refuses_bad_sizes_and_sizes_with_a_world(tmp_path: Path) -> None:
    for args, message in ((["--drones", "0"], "--drones: '0' is not a whole number"),
                          (["--map-size-m", "20"], "--map-size-m must be from 200"),
                          (["--map-size-m", "200", "--levels", "extreme", "--families",
                            "area_search", "--sessions-per-cell", "1"],
                           "choose a larger --map-size-m"),
                          (["--drones", "4", "--world", str(DEFAULTS)],
                           "a --world file keeps its own drones")):
        result = _cli("bench", "generate", "--no-verify", "--out", str(tmp_path / "o"), *args)
        assert result.returncode == 2 and message in result.stderr, result.stderr
    assert not (tmp_path / "o").exists()
