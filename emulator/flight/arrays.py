"""Small array helpers for the per-step hot path (cheaper than ndarray.any / flatnonzero)."""

from __future__ import annotations

from functools import lru_cache

import numpy as np

__all__ = ["any_true", "count_nonzero", "indices", "step_offsets_s", "steps_done"]

try:  # numpy's C function itself, without the Python wrapper around it (~0.3 us a call)
    from numpy._core._multiarray_umath import count_nonzero
except ImportError:  # pragma: no cover - numpy < 2
    count_nonzero = np.count_nonzero
_count = count_nonzero


def any_true(mask: np.ndarray) -> bool:
    return bool(_count(mask))


def indices(mask: np.ndarray) -> np.ndarray:
    return mask.nonzero()[0]


@lru_cache(maxsize=512)
def step_offsets_s(count: int, dt_s: float) -> np.ndarray:
    """(count, 1, 1) read-only: the times of steps 1..count after a start, i * dt_s, shaped
    to scale an (n, 3) velocity into count positions."""
    offsets = np.arange(1, count + 1)[:, None, None] * dt_s
    offsets.setflags(write=False)
    return offsets


@lru_cache(maxsize=512)
def steps_done(count: int, first: int, every: int) -> np.ndarray:
    """(count,) read-only: for each step 0..count-1 of a stretch whose first periodic step
    (one every `every` steps) is step `first` (0 <= first < every), how many periodic steps ran
    at or before it: the row that holds the value at that step in an array of the value before
    the stretch and after each periodic step."""
    done = (np.arange(count) + (every - first)) // every
    done.setflags(write=False)
    return done
