"""Hypothesis draws that depend on the seed alone, not on what else the session imported.

Since 6.131 Hypothesis sometimes draws a literal found in the source of the project's modules
that are imported at the time (`sys.modules`, its "local constants"). The pool therefore
changes with the test files collected in the same session (tests/test_compat_client.py
imports the benchmark server and its constants) and with any edit of the project's source,
and a derandomized or seeded @given function draws other examples. Inside
`seed_only_draws()` that pool is empty, so the examples depend on the seed and the
Hypothesis version only. The pool is an internal of Hypothesis (6.170 has no setting for
it): if it moves, this fails loudly (AttributeError) instead of silently drawing
context-dependent examples again.

tests/conftest.py runs every test of the suite inside `seed_only_draws()` (its autouse
fixture `hypothesis_seed_only_draws`), so no test needs to enter it itself;
`source_constant_draws()` gives a block Hypothesis's own pool back, for the test that shows
the difference.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator

from hypothesis.internal.conjecture import providers
from hypothesis.internal.constants_ast import Constants

__all__ = ["seed_only_draws", "seed_only_draws_active", "source_constant_draws"]

_HYPOTHESIS_LOCAL_CONSTANTS = providers._get_local_constants


def _no_local_constants() -> Constants:
    return Constants()


@contextlib.contextmanager
def _local_constants_from(collect: Callable[[], Constants]) -> Iterator[None]:
    outer = providers._get_local_constants
    cache = providers.CONSTANTS_CACHE.cache  # (type, constraints) -> (global, local) pools
    providers._get_local_constants = collect
    cache.clear()
    try:
        yield
    finally:
        providers._get_local_constants = outer
        cache.clear()


def seed_only_draws() -> contextlib.AbstractContextManager[None]:
    """Hypothesis draws no constant of the project's source inside the block."""
    return _local_constants_from(_no_local_constants)


def source_constant_draws() -> contextlib.AbstractContextManager[None]:
    """Hypothesis draws constants of the imported project source inside the block (its
    default, undone by `seed_only_draws()`)."""
    return _local_constants_from(_HYPOTHESIS_LOCAL_CONSTANTS)


def seed_only_draws_active() -> bool:
    """Whether Hypothesis draws no constant of the project's source here."""
    return providers._get_local_constants is _no_local_constants
