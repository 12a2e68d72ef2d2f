"""The rate at which the console pushes live frames to its pages, and its bounds."""

from __future__ import annotations

import math

__all__ = ["DEFAULT_RATE_HZ", "check_rate_hz"]

DEFAULT_RATE_HZ = 10.0


def check_rate_hz(rate_hz: float) -> float:
    """`rate_hz` if it is a frame rate pages can take (0.5 to 60 Hz), else ValueError."""
    if not (math.isfinite(rate_hz) and 0.5 <= rate_hz <= 60.0):
        raise ValueError(f"rate_hz must be within 0.5..60, got {rate_hz}")
    return rate_hz
