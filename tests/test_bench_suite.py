"""The shipped suite: 125 sessions of 20 tasks that load cleanly, cover the check endpoints,
and regenerate byte for byte from their seeds."""

from __future__ import annotations

from collections import Counter

import pytest

from benchmark.authoring.scenarios import LEVELS, SESSION_INDICES, all_session_keys, session_id
from benchmark.authoring.session_file import dump_session, load_session
from benchmark.authoring.suite import SESSIONS_DIR, suite_paths
from benchmark.running.generation import generate_session
from benchmark.scoring.validators import endpoints_used, leaf_count


@pytest.mark.slow
def test_the_full_suite_loads_and_covers_the_endpoints() -> None:
    paths, limit = suite_paths("full")
    assert limit is None and len(paths) == 125
    assert [p.stem for p in paths] == [session_id(*k) for k in all_session_keys()]
    endpoints: set[str] = set()
    categories: Counter[str] = Counter()
    families: Counter[str] = Counter()
    checks = 0
    for path in paths:
        session = load_session(path)
        assert len(session.tasks) == 20, path
        families[session.family] += 1
        for task in session.tasks:
            assert task.error is None, task.error
            assert task.oracle is not None and task.budget is not None
            assert task.checks is not None
            checks += leaf_count(task.checks)
            endpoints |= endpoints_used(task.checks)
            categories[task.category] += 1
    assert len(endpoints) >= 23, sorted(endpoints)
    assert {"moving_target_tracked", "moving_target_reached_in_zone"} <= endpoints
    assert set(categories) == {"basic_operations", "navigation", "search",
                               "multi_drone_coordination", "delivery", "communication",
                               "battery_management", "target_tracking", "resilience"}
    assert families == dict.fromkeys(("area_search", "area_assignment_and_patrol",
                                      "target_assignment", "target_tracking", "resilience"), 25)
    assert checks >= 4 * 2500


def test_unverified_generation_reproduces_a_shipped_session() -> None:
    """With every first draw passing, the oracle changes nothing: drawing alone gives the
    shipped file, on any machine."""
    shipped = (SESSIONS_DIR / "area_assignment_and_patrol-easy-2.json").read_text()
    again = dump_session(generate_session("area_assignment_and_patrol", "easy", 2,
                                          verify=False))
    assert again == shipped


@pytest.mark.mavsdk
@pytest.mark.slow
def test_verified_generation_reproduces_a_shipped_session() -> None:
    shipped = (SESSIONS_DIR / "area_search-easy-1.json").read_text()
    lines: list[str] = []
    again = dump_session(generate_session("area_search", "easy", 1, progress=lines.append))
    assert again == shipped, lines


@pytest.mark.parametrize("family", ["target_tracking", "resilience"])
@pytest.mark.slow
def test_every_tracking_and_resilience_session_redraws_from_its_seed(family: str) -> None:
    """Every first draw of the 25 sessions of these families passed the oracle (faults
    striking, for resilience), so drawing alone gives the shipped files."""
    for level in LEVELS:
        for index in SESSION_INDICES:
            name = f"{family}-{level}-{index}"
            again = dump_session(generate_session(family, level, index, verify=False))
            assert again == (SESSIONS_DIR / f"{name}.json").read_text(), name


@pytest.mark.mavsdk
def test_the_oracle_proves_the_first_tracking_tasks_again() -> None:
    """The first tasks of a tracking session, flown again by the oracle: the same tasks."""
    shipped = load_session(SESSIONS_DIR / "target_tracking-easy-2.json").data["tasks"][:3]
    lines: list[str] = []
    again = generate_session("target_tracking", "easy", 2, tasks=3, progress=lines.append)
    assert again["tasks"] == shipped, lines


@pytest.mark.mavsdk
def test_the_oracle_proves_the_first_resilience_tasks_again() -> None:
    """The first tasks of a resilience session, flown again by the oracle with their faults
    striking: the same tasks, none redrawn."""
    shipped = load_session(SESSIONS_DIR / "resilience-easy-1.json").data["tasks"][:4]
    assert any("faults" in task for task in shipped)
    lines: list[str] = []
    again = generate_session("resilience", "easy", 1, tasks=4, progress=lines.append)
    assert again["tasks"] == shipped, lines
