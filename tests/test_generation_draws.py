"""Generation for researchers: private splits (`--seed SECRET`), cells, counts, template
folders and worlds of one's own; suite fingerprints on every record and a report that refuses
to pool two suites."""

from __future__ import annotations

import collections
import hashlib
import json
import subprocess
from pathlib import Path
from typing import Any

import pytest

from benchmark.authoring.fingerprint import (
    MixedSuitesError,
    check_poolable,
    session_fingerprint,
    suite_fingerprint_of_files,
)
from benchmark.authoring.scenarios import FAMILIES, LEVELS, generate_world, session_seed
from benchmark.authoring.session_file import load_session
from benchmark.authoring.suite import SESSIONS_DIR, Draw, suite_keys
from benchmark.running.episode import base_record, error_record
from benchmark.running.generation import generate_session
from tests.cli_fixtures import run_in_process

ROOT = Path(__file__).resolve().parent.parent


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    """`mavswarm ARGS` through its main in this process (what it prints and its status are the
    command's; a process of its own would add only its start-up)."""
    return run_in_process(*args, cwd=ROOT)


def _stats(world: dict[str, Any]) -> tuple[Any, ...]:
    area = {"circle": "area", "polygon": "area"}  # an area's shape is itself a random draw
    kinds = collections.Counter(area.get(t["type"], t["type"]) for t in world["targets"])
    return (world["map_size_m"], len(world["drones"]), sorted(kinds.items()),
            len(world["obstacles"]), world["task_type"])


# ------------------------------------------------------------------ private splits
def test_a_private_split_has_the_public_distribution_but_other_sessions() -> None:
    for family in FAMILIES:
        for level in LEVELS:
            public = generate_world(family, level, 1)
            private = generate_world(family, level, 1, secret="lab-7")
            assert _stats(private) == _stats(public), (family, level)
            assert private["id"] == public["id"]
            assert private["seed"] != public["seed"]
            assert private["drones"] != public["drones"] or private["targets"] != public[
                "targets"]
            assert generate_world(family, level, 1, secret="lab-7") == private
    assert session_seed("area_search", "easy", 1, secret="other") != session_seed(
        "area_search", "easy", 1, secret="lab-7")


def test_a_private_split_draws_task_categories_as_the_public_one_does() -> None:
    shares: dict[str, collections.Counter[str]] = {"": collections.Counter(),
                                                   "lab-7": collections.Counter()}
    for secret, counter in shares.items():
        for family in FAMILIES:
            for level in ("easy", "hard"):
                session = generate_session(family, level, 1, verify=False, secret=secret,
                                           progress=lambda _: None)
                counter.update(f"{family}/{t['category']}" for t in session["tasks"])
    public, private = shares[""], shares["lab-7"]
    assert sum(public.values()) == sum(private.values()) == len(FAMILIES) * 2 * 20
    for family in FAMILIES:  # each family's heavy category dominates in both
        top = {c.most_common(1)[0][0] for c in (
            collections.Counter({k: v for k, v in s.items() if k.startswith(family + "/")})
            for s in (public, private))}
        assert len(top) == 1, (family, top)
    for key in public | private:
        assert abs(public[key] - private[key]) <= 12, key


def test_cells_counts_and_bad_names() -> None:
    keys = suite_keys(Draw(families=("resilience",), levels=("easy", "hard"),
                           sessions_per_cell=7))
    assert keys == [("resilience", lv, i) for lv in ("easy", "hard") for i in range(1, 8)]
    assert len(suite_keys(Draw())) == 125
    with pytest.raises(ValueError, match="unknown family 'skydiving'"):
        suite_keys(Draw(families=("skydiving",)))
    result = _cli("bench", "generate", "--no-verify", "--out", "/tmp/never", "--levels",
                  "medium")
    assert result.returncode == 2 and "unknown level 'medium'" in result.stderr


def test_generate_cli_draws_a_private_cell_with_fewer_tasks(tmp_path: Path) -> None:
    result = _cli("bench", "generate", "--no-verify", "--out", str(tmp_path), "--seed",
                  "s3cret", "--families", "target_assignment", "--levels", "easy",
                  "--sessions-per-cell", "6", "--tasks-per-session", "3")
    assert result.returncode == 0, result.stderr
    files = sorted(tmp_path.glob("*.json"))
    assert [f.stem for f in files] == [f"target_assignment-easy-{i}" for i in range(1, 7)]
    first = json.loads(files[0].read_text())
    assert len(first["tasks"]) == 3
    assert files[0].read_bytes() != (SESSIONS_DIR / files[0].name).read_bytes()
    again = tmp_path / "again"
    _cli("bench", "generate", "--no-verify", "--out", str(again), "--seed", "s3cret",
         "--families", "target_assignment", "--levels", "easy", "--sessions-per-cell", "1",
         "--tasks-per-session", "3")
    assert (again / files[0].name).read_bytes() == files[0].read_bytes()


def test_user_templates_are_proved_by_the_derived_oracle(tmp_path: Path) -> None:
    folder = tmp_path / "templates"
    folder.mkdir()
    (folder / "checkpoint_photo.json").write_text(json.dumps({
        "format": "mavswarm.template/1", "id": "checkpoint_photo", "category": "search",
        "entities": [{"group": "drone", "kind": "drone"}],
        "phrasings": ["Fly {drone_name} to ({randx_cp:150:450}, {randy_cp:150:450}) at "
                      "{randz_cp:15:20} m and take a photo there."],
        "checks": [{"endpoint": "drone_has_visited_position", "parameters": {
            "drone_id": "{drone_id}", "x": "{randx_cp}", "y": "{randy_cp}", "z": "{randz_cp}",
            "tolerance": 3.0}},
            {"endpoint": "drone_has_taken_photo", "parameters": {"drone_id": "{drone_id}"}}],
        "budget": {"steps": 3}}))
    result = _cli("bench", "generate", "--out", str(tmp_path / "out"), "--families",
                  "area_search", "--levels", "easy", "--sessions-per-cell", "1",
                  "--tasks-per-session", "2", "--templates", str(folder),
                  "--replace-templates")
    assert result.returncode == 0, result.stdout + result.stderr
    session = json.loads((tmp_path / "out" / "area_search-easy-1.json").read_text())
    assert [t["template"] for t in session["tasks"]] == ["checkpoint_photo"] * 2
    assert all(t["oracle"] is None for t in session["tasks"])
    assert "NOT proved" not in result.stdout + result.stderr


def test_a_bad_template_folder_is_refused_naming_the_file(tmp_path: Path) -> None:
    (tmp_path / "broken.json").write_text(json.dumps({"id": "x", "category": "search"}))
    result = _cli("bench", "generate", "--no-verify", "--out", str(tmp_path / "out"),
                  "--templates", str(tmp_path))
    assert result.returncode == 2
    assert f"{tmp_path / 'broken.json'}: phrasings: Field required" in result.stderr
    assert not (tmp_path / "out").exists()


def test_tasks_for_a_world_of_ones_own(tmp_path: Path) -> None:
    world = tmp_path / "my_world.json"
    data = json.loads((SESSIONS_DIR / "area_search-easy-2.json").read_text())
    world.write_text(json.dumps({**data, "id": "my-field", "tasks": []}))
    result = _cli("bench", "generate", "--no-verify", "--world", str(world), "--out",
                  str(tmp_path / "out"), "--tasks-per-session", "4", "--seed", "x")
    assert result.returncode == 0, result.stderr
    made = json.loads((tmp_path / "out" / "my-field.json").read_text())
    assert made["obstacles"] == data["obstacles"] and made["drones"] == data["drones"]
    assert len(made["tasks"]) == 4


# ------------------------------------------------------------------ fingerprints
def test_a_session_fingerprint_is_the_hash_of_its_file() -> None:
    path = SESSIONS_DIR / "area_search-easy-1.json"
    digest = hashlib.sha256(path.read_bytes()).hexdigest()[:16]
    assert session_fingerprint(load_session(path)) == digest
    one = suite_fingerprint_of_files([path])
    assert one != suite_fingerprint_of_files([path, SESSIONS_DIR / "area_search-easy-2.json"])


def _records(fingerprint: str, agent: str = "oracle") -> list[dict[str, Any]]:
    return [error_record(base_record(session_id="area_search-easy-1", family="area_search",
                                     level="easy", task_id=f"t0{k}", template="x",
                                     category="search", agent=agent, trial=0,
                                     fingerprint=fingerprint), "not run") for k in (1, 2)]


def test_records_of_two_suites_are_not_pooled_unless_asked() -> None:
    assert check_poolable(_records("aaaa") + _records("aaaa", "noop")) is not None
    with pytest.raises(MixedSuitesError, match="session area_search-easy-1 was run from 2"):
        check_poolable(_records("aaaa") + _records("bbbb", "noop"))
    assert check_poolable(_records("aaaa") + _records("bbbb", "noop"), allow_mixed=True)
    assert check_poolable([{"session": "s", "fingerprint": None}]) is None


def test_bench_report_refuses_to_pool_two_fingerprints(tmp_path: Path) -> None:
    paths = []
    for name, fp in (("public", "1111"), ("private", "2222")):
        folder = tmp_path / name
        folder.mkdir()
        (folder / "results.jsonl").write_text(
            "".join(json.dumps(r) + "\n" for r in _records(fp, agent=f"oracle-{name}")))
        paths.append(str(folder / "results.jsonl"))
    refused = _cli("bench", "report", *paths, "--out", str(tmp_path / "r1"))
    assert refused.returncode == 2
    assert "the results mix suites" in refused.stderr and "--allow-mixed" in refused.stderr
    assert not (tmp_path / "r1").exists()
    pooled = _cli("bench", "report", *paths, "--out", str(tmp_path / "r2"), "--allow-mixed")
    assert pooled.returncode == 0, pooled.stderr
    assert (tmp_path / "r2" / "report.md").exists()
