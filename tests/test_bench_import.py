"""MultiUAV-Plat session files, tasks and check trees included, run here."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from benchmark.authoring.importer import SessionImportError, import_session, import_session_file
from benchmark.authoring.session_file import load_session
from tests.bench_fixtures import reference_session


def _reference_task(drone: str, target: str) -> dict:
    return {
        "id": "a1b2c3d4", "name": "Target Inspection 1", "content": "Inspect the target.",
        "content_aliases": ["Look at the target."], "difficulty": "medium",
        "related_apis": [], "commands": ["take_off", "move_to"],
        "execution_check_apis": {"logic": "and", "checks": [
            {"endpoint": "/check/drone_has_taken_off",
             "parameters": {"drone_id": drone, "min_altitude": "12.0"}},
            {"endpoint": "/check/target_is_reached_by_drone",
             "parameters": {"drone_id": drone, "target_id": target, "since_timestamp": 0}},
            {"endpoint": "/check/drone_has_landed",
             "parameters": {"drone_id": drone, "max_altitude": 1.0}},
            {"endpoint": "/check/drone_on_ground",
             "parameters": {"drone_id": drone}, "expect": "false"},
        ]},
    }


@pytest.fixture
def reference() -> dict:
    data = reference_session()
    drone, target = data["drones"][0]["id"], data["targets"][0]["id"]
    bad = _reference_task(drone, target)
    bad["id"] = "deadbeef"
    bad["execution_check_apis"]["checks"][0]["endpoint"] = "/check/drone_is_happy"
    data["tasks"] = [_reference_task(drone, target), bad]
    return data


def test_import_keeps_tasks_and_checks(reference: dict, tmp_path: Path) -> None:
    src = tmp_path / "ref.json"
    src.write_text(json.dumps(reference))
    path, notes = import_session_file(src, tmp_path / "out")
    session = load_session(path)
    assert len(session.scenario.vehicles) == 4 and session.level == "imported"
    good, bad = session.tasks
    assert good.error is None and good.text == "Inspect the target."
    assert good.aliases == ("Look at the target.",) and good.oracle is None
    endpoints = [leaf.endpoint for leaf in good.checks.checks]  # type: ignore[union-attr]
    assert endpoints == ["drone_has_taken_off", "target_is_reached_by_drone",
                         "drone_has_landed", "drone_on_ground"]
    assert good.checks.checks[0].parameters["min_altitude"] == 12.0  # type: ignore[union-attr]
    assert good.checks.checks[3].expect is False  # type: ignore[union-attr]
    assert bad.error is not None and "drone_is_happy" in bad.error and "deadbeef" in bad.error
    assert any("deadbeef" in n for n in notes)


def test_import_refuses_what_is_not_a_reference_session(tmp_path: Path) -> None:
    with pytest.raises(SessionImportError, match="drones"):
        import_session({"name": "x"}, source="x.json")
    with pytest.raises(SessionImportError, match="not valid JSON"):
        bad = tmp_path / "b.json"
        bad.write_text("[1,")
        import_session_file(bad, tmp_path)
