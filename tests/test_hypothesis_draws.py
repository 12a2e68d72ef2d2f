"""tests/hypothesis_draws.py: a seeded draw gives the same examples whatever the session imports,
and tests/conftest.py runs every test of the suite that way."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest
from hypothesis import Phase, given, seed, settings
from hypothesis import strategies as st

from tests.hypothesis_draws import seed_only_draws, seed_only_draws_active, source_constant_draws


def _literals(first: float) -> frozenset[float]:
    """A probe module's literals: none a bound or a round number Hypothesis draws anyway."""
    return frozenset(round(first + 0.7919 * i, 4) for i in range(400))


# Hypothesis keeps what its own pool once saw: each test imports literals of its own
PROBE_LITERALS = _literals(9100.3173)
SESSION_LITERALS = _literals(7100.3173)


# around the literals, the bounds (which Hypothesis draws early) none of them
PROBE_RANGE = st.floats(min(PROBE_LITERALS) - 0.5, max(PROBE_LITERALS) + 0.5)


def _draws() -> list[float]:
    out: list[float] = []

    @seed(7)
    @settings(database=None, deadline=None, max_examples=60, phases=(Phase.generate,))
    @given(st.lists(st.floats(allow_nan=False), min_size=20, max_size=20))
    def collect(values: list[float]) -> None:
        out.extend(values)

    collect()
    return out


def _import_module_with_constants(directory: Path, literals: frozenset[float]) -> str:
    """A module of the project's kind (not under tests/) full of float literals. It stays
    imported: Hypothesis tells new modules by the length of `sys.modules` (one removed and
    one added go unseen), and its own pool never forgets a literal anyway."""
    name = f"constants_pool_probe_{directory.name}"
    path = directory / f"{name}.py"
    values = ", ".join(map(repr, sorted(literals)))
    path.write_text(f"VALUES = [{values}]\n")
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return name


def test_seeded_draws_do_not_follow_the_modules_imported(tmp_path: Path) -> None:
    with seed_only_draws():
        before = _draws()
    with source_constant_draws():
        plain_before = _draws()
    name = _import_module_with_constants(tmp_path, SESSION_LITERALS)
    assert name in sys.modules
    with seed_only_draws():
        assert _draws() == before
    # with Hypothesis's own pool, it now also draws the new module's literals
    with source_constant_draws():
        plain_after = _draws()
    assert plain_after != plain_before
    assert not SESSION_LITERALS & set(plain_before)
    assert SESSION_LITERALS & set(plain_after)


def test_every_test_of_the_suite_runs_inside_seed_only_draws(
        request: pytest.FixtureRequest) -> None:
    assert "hypothesis_seed_only_draws" in request.fixturenames
    assert seed_only_draws_active()
    with source_constant_draws():
        assert not seed_only_draws_active()
        with seed_only_draws():  # nested, as tests that enter it themselves do
            assert seed_only_draws_active()
        assert not seed_only_draws_active()
    assert seed_only_draws_active()


@pytest.fixture(scope="module")
def probe_module(tmp_path_factory: pytest.TempPathFactory) -> str:
    return _import_module_with_constants(tmp_path_factory.mktemp("probe"), PROBE_LITERALS)


@seed(7)
@settings(database=None, deadline=None, max_examples=300, phases=(Phase.generate,))
@given(value=PROBE_RANGE)
def test_an_ordinary_given_test_draws_no_literal_of_the_imported_source(
        probe_module: str, value: float) -> None:
    """Nothing but the decorators: a module full of literals is imported (as the session's
    other test files import the project's), and not one of them is drawn. With Hypothesis's
    own pool about one draw in twenty is one (test_source_pool_would_give_the_probe_literals)."""
    assert probe_module in sys.modules
    assert value not in PROBE_LITERALS


def test_source_pool_would_give_the_probe_literals(probe_module: str) -> None:
    """The same strategy and seed, run with Hypothesis's own pool, draws the probe's literals:
    the test above would fail without the suite-wide `seed_only_draws()`."""
    out: list[float] = []

    @seed(7)
    @settings(database=None, deadline=None, max_examples=300, phases=(Phase.generate,))
    @given(value=PROBE_RANGE)
    def collect(value: float) -> None:
        out.append(value)

    with source_constant_draws():
        collect()
    assert len(PROBE_LITERALS.intersection(out)) >= 3
