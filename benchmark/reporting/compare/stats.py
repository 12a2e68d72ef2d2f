"""Statistics for comparing benchmark runs: the exact McNemar test on paired outcomes and
percentile bootstrap intervals clustered by session.

Why clustered: the tasks of one session share its world (the same drones, targets, obstacles
and map), so an agent that misreads a world tends to fail several of its tasks together.
Resampling tasks one by one would treat those correlated outcomes as independent and give
intervals that are too narrow; resampling whole sessions keeps the correlation in every
resample. Every run of a comparison is resampled with the *same* session draws, so the
difference of two runs' rates in one resample is a paired bootstrap of the difference.

Draws come from ``numpy.random.default_rng(seed)``: the same seed gives the same intervals.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from math import comb

import numpy as np

__all__ = [
    "DEFAULT_CONFIDENCE",
    "DEFAULT_RESAMPLES",
    "DEFAULT_SEED",
    "ClusterBootstrap",
    "Estimate",
    "mcnemar_exact_p",
]

DEFAULT_RESAMPLES = 2000
DEFAULT_SEED = 0
DEFAULT_CONFIDENCE = 0.95


def mcnemar_exact_p(fail_to_pass: int, pass_to_fail: int) -> float:
    """Exact two-sided McNemar p-value: under "no difference" each discordant pair is
    fail->pass or pass->fail with probability 1/2, so the smaller count is binomial(n, 1/2)
    with n the discordant pairs; p = min(1, 2 * P(X <= smaller)). 1.0 when n is 0."""
    for name, value in (("fail_to_pass", fail_to_pass), ("pass_to_fail", pass_to_fail)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            raise ValueError(f"McNemar count {name!r} must be a non-negative integer, "
                             f"got {value!r}")
    n = fail_to_pass + pass_to_fail
    if n == 0:
        return 1.0
    smaller = min(fail_to_pass, pass_to_fail)
    tail = sum(comb(n, i) for i in range(smaller + 1))
    return min(1.0, 2 * tail / 2**n)  # exact integers; one rounding at the division


@dataclass(frozen=True)
class Estimate:
    """A point estimate with its percentile bootstrap interval."""

    value: float
    low: float
    high: float


class ClusterBootstrap:
    """Resamples of `clusters` sessions drawn with replacement, shared by every statistic
    computed from it: ``weights[b, s]`` is how often session s was drawn in resample b."""

    def __init__(self, clusters: int, *, resamples: int = DEFAULT_RESAMPLES,
                 seed: int = DEFAULT_SEED, confidence: float = DEFAULT_CONFIDENCE) -> None:
        if isinstance(clusters, bool) or not isinstance(clusters, int) or clusters < 1:
            raise ValueError(f"the bootstrap needs at least one session, got {clusters!r}")
        if isinstance(resamples, bool) or not isinstance(resamples, int) or resamples < 100:
            raise ValueError(f"bootstrap resamples must be an integer >= 100, got {resamples!r}")
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise ValueError(f"the bootstrap seed must be a non-negative integer, got {seed!r}")
        if not 0.5 <= confidence < 1.0:
            raise ValueError(f"confidence must be in [0.5, 1), got {confidence!r}")
        self.clusters = clusters
        self.resamples = resamples
        self.seed = seed
        self.confidence = confidence
        draws = np.random.default_rng(seed).integers(0, clusters, size=(resamples, clusters))
        flat = draws + np.arange(resamples)[:, None] * clusters
        self.weights = np.bincount(flat.ravel(), minlength=resamples * clusters).reshape(
            resamples, clusters).astype(np.float64)

    def _vector(self, values: Sequence[float] | np.ndarray, name: str) -> np.ndarray:
        array = np.asarray(values, dtype=np.float64)
        if array.shape != (self.clusters,):
            raise ValueError(f"{name} must hold one value per session ({self.clusters}), "
                             f"got shape {array.shape}")
        return array

    def ratio_draws(self, numerator: Sequence[float] | np.ndarray,
                    denominator: Sequence[float] | np.ndarray) -> np.ndarray:
        """The ratio sum(numerator) / sum(denominator) in every resample (NaN where a
        resample drew no denominator)."""
        num = self.weights @ self._vector(numerator, "numerator")
        den = self.weights @ self._vector(denominator, "denominator")
        out = np.full(self.resamples, np.nan)
        np.divide(num, den, out=out, where=den > 0)
        return out

    def interval(self, value: float, draws: np.ndarray) -> Estimate:
        """`value` with the central `confidence` percentile interval of `draws`."""
        finite = draws[np.isfinite(draws)]
        if finite.size == 0:
            return Estimate(value, value, value)
        tail = (1.0 - self.confidence) / 2.0 * 100.0
        low, high = np.percentile(finite, [tail, 100.0 - tail])
        return Estimate(value, float(low), float(high))

    def ratio(self, numerator: Sequence[float] | np.ndarray,
              denominator: Sequence[float] | np.ndarray) -> tuple[Estimate, np.ndarray]:
        """The ratio of sums with its interval, and its draws (for paired differences)."""
        num = self._vector(numerator, "numerator")
        den = self._vector(denominator, "denominator")
        total = float(den.sum())
        value = float(num.sum()) / total if total else 0.0
        draws = self.ratio_draws(num, den)
        return self.interval(value, draws), draws

    def difference(self, value: float, draws_a: np.ndarray, draws_b: np.ndarray) -> Estimate:
        """`value` (a - b) with the interval of the paired resample differences."""
        return self.interval(value, draws_a - draws_b)
