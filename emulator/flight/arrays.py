"""Small array helpers for the per-step hot path (cheaper than ndarray.any / flatnonzero)."""

from __future__ import annotations

import numpy as np

__all__ = ["any_true", "indices"]

_count = np.count_nonzero


def any_true(mask: np.ndarray) -> bool:
    return bool(_count(mask))


def indices(mask: np.ndarray) -> np.ndarray:
    return mask.nonzero()[0]
