"""tests/hypothesis_draws.py: a seeded draw gives the same examples whatever the session imports."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

from hypothesis import Phase, given, seed, settings
from hypothesis import strategies as st

from tests.hypothesis_draws import seed_only_draws


def _draws() -> list[float]:
    out: list[float] = []

    @seed(7)
    @settings(database=None, deadline=None, max_examples=60, phases=(Phase.generate,))
    @given(st.lists(st.floats(allow_nan=False), min_size=20, max_size=20))
    def collect(values: list[float]) -> None:
        out.extend(values)

    collect()
    return out


def _import_module_with_constants(directory: Path) -> str:
    """A module of the project's kind (not under tests/) full of float literals."""
    name = "constants_pool_probe"
    path = directory / f"{name}.py"
    path.write_text("VALUES = [" + ", ".join(f"{9100.25 + i}" for i in range(400)) + "]\n")
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return name


def test_seeded_draws_do_not_follow_the_modules_imported(tmp_path: Path) -> None:
    with seed_only_draws():
        before = _draws()
    plain_before = _draws()
    name = _import_module_with_constants(tmp_path)
    try:
        with seed_only_draws():
            assert _draws() == before
        # without it, hypothesis now also draws the new module's literals
        plain_after = _draws()
        assert plain_after != plain_before
        assert any(9100.25 <= v < 9100.25 + 400 and v == int(v - 0.25) + 0.25
                   for v in plain_after)
    finally:
        del sys.modules[name]
