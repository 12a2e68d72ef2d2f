"""tests/hypothesis_draws.py: every @given test is derandomized with no database, and draws
the same examples whatever the session imported before it, because the whole project is
imported before the first test."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from hypothesis import settings

from tests.hypothesis_draws import PROFILE, ROOT, import_project_source

# A process that imports `first`, then (or not) the whole project, then draws 300 floats from
# a range full of the project's literals with the suite's profile: the draws, as JSON.
DRAW = """
import importlib, json, sys
from hypothesis import given, settings, strategies as st
from tests.hypothesis_draws import import_project_source, load_profile
load_profile()
for name in sys.argv[1].split(","):
    importlib.import_module(name)
if sys.argv[2] == "whole":
    import_project_source()
out = []

@settings(max_examples=300)
@given(st.floats(0.0, 100.0))
def collect(value):
    out.append(value)

collect()
print(json.dumps(out))
"""


def _draws(first: str, whole: bool) -> list[float]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-c", DRAW, first, "whole" if whole else "part"],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=300,
                          check=False)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def test_the_suite_profile_is_derandomized_without_a_database() -> None:
    assert settings.get_current_profile_name() == PROFILE
    assert settings.default.derandomize
    assert settings.default.database is None
    assert settings.default.deadline is None


def test_the_whole_project_is_imported_before_the_first_test() -> None:
    names = import_project_source()
    assert {"emulator.swarm", "mavlink_gateway.fleet", "benchmark.running.episode"} <= set(names)
    assert all(name in sys.modules for name in names)
    assert not any(name.endswith("__main__") for name in names)


@pytest.mark.slow
def test_draws_do_not_depend_on_what_was_imported_first() -> None:
    """Two sessions that imported different parts of the project first (as sessions that
    collected different test files do) draw the same examples once the whole project is
    imported; without that, the literals Hypothesis borrows from the imported source differ
    and so do the draws."""
    few = _draws("emulator.geo", whole=True)
    many = _draws("benchmark.running.episode,mavswarm.cli,llm_tools.registry", whole=True)
    assert len(few) == 300 and few == many
    assert _draws("emulator.geo", whole=False) != few

