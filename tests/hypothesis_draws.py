"""Hypothesis draws that depend on the seed alone, not on what else the session imported.

Since 6.131 Hypothesis sometimes draws a literal found in the source of the project's modules
that are imported at the time (`sys.modules`, its "local constants"). The pool therefore
changes with the test files collected in the same session (tests/test_compat_client.py
imports the benchmark server and its constants) and with any edit of the project's source,
and a derandomized or seeded @given function draws other examples. Inside
`seed_only_draws()` that pool is empty, so the examples depend on the seed and the
Hypothesis version only. The pool is an internal of Hypothesis: if it moves, this fails
loudly (AttributeError) instead of silently drawing context-dependent examples again.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

from hypothesis.internal.conjecture import providers
from hypothesis.internal.constants_ast import Constants

__all__ = ["seed_only_draws"]


def _no_local_constants() -> Constants:
    return Constants()


@contextlib.contextmanager
def seed_only_draws() -> Iterator[None]:
    """Hypothesis draws no constant of the project's source inside the block."""
    collect = providers._get_local_constants
    cache = providers.CONSTANTS_CACHE.cache  # (type, constraints) -> (global, local) pools
    providers._get_local_constants = _no_local_constants
    cache.clear()
    try:
        yield
    finally:
        providers._get_local_constants = collect
        cache.clear()
