"""Small array helpers for the per-step hot path (cheaper than ndarray.any / flatnonzero)."""

from __future__ import annotations

import numpy as np

__all__ = ["any_true", "count_nonzero", "indices"]

try:  # numpy's C function itself, without the Python wrapper around it (~0.3 us a call)
    from numpy._core._multiarray_umath import count_nonzero
except ImportError:  # pragma: no cover - numpy < 2
    count_nonzero = np.count_nonzero
_count = count_nonzero


def any_true(mask: np.ndarray) -> bool:
    return bool(_count(mask))


def indices(mask: np.ndarray) -> np.ndarray:
    return mask.nonzero()[0]
