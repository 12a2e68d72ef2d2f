"""The statistics of `bench compare` against known values: the exact McNemar p-value of small
tables computed by hand, and session-clustered bootstrap intervals that cover the true rate
at about their nominal 95 % in simulation (also when a session's tasks are correlated)."""

from __future__ import annotations

import numpy as np
import pytest

from benchmark.reporting.compare.stats import ClusterBootstrap, mcnemar_exact_p


def test_mcnemar_exact_p_of_small_tables_by_hand() -> None:
    # 6 fail->pass, 1 pass->fail: n = 7 discordant pairs, P(X <= 1) = (C(7,0) + C(7,1)) / 2^7
    # = 8 / 128, two-sided 16 / 128 = 0.125.
    assert mcnemar_exact_p(6, 1) == pytest.approx(0.125, abs=1e-15)
    assert mcnemar_exact_p(1, 6) == pytest.approx(0.125, abs=1e-15)
    # 5 and 0: 2 * (1 / 32) = 0.0625; 10 and 0: 2 / 1024.
    assert mcnemar_exact_p(5, 0) == pytest.approx(0.0625, abs=1e-15)
    assert mcnemar_exact_p(0, 10) == pytest.approx(2 / 1024, abs=1e-15)
    # Balanced and empty tables: no evidence at all.
    assert mcnemar_exact_p(3, 3) == 1.0
    assert mcnemar_exact_p(0, 0) == 1.0


@pytest.mark.parametrize(("up", "down"), [(441, 31), (12, 9), (0, 3), (150, 151), (2, 40)])
def test_mcnemar_matches_scipys_binomial_test(up: int, down: int) -> None:
    from scipy.stats import binomtest
    expected = binomtest(up, up + down, 0.5, alternative="two-sided").pvalue
    assert mcnemar_exact_p(up, down) == pytest.approx(expected, rel=1e-9, abs=1e-300)


@pytest.mark.parametrize("bad", [-1, 1.5, True, "3", None])
def test_mcnemar_refuses_counts_that_are_not_counts(bad: object) -> None:
    with pytest.raises(ValueError, match="non-negative integer"):
        mcnemar_exact_p(bad, 1)  # type: ignore[arg-type]


def _coverage(sessions: int, tasks: int, draw_rates: np.ndarray, true_rate: float,
              rng: np.random.Generator) -> float:
    """Share of simulated data sets whose 95 % interval holds `true_rate`; each data set has
    `sessions` sessions of `tasks` tasks, session s passing each task with draw_rates[k, s]."""
    boot = ClusterBootstrap(sessions, resamples=400, seed=1)
    hits = 0
    for rates in draw_rates:
        passed = rng.binomial(tasks, rates)
        estimate, _ = boot.ratio(passed, np.full(sessions, tasks))
        hits += estimate.low <= true_rate <= estimate.high
    return hits / len(draw_rates)


def test_bootstrap_interval_covers_the_true_rate_at_about_95_percent() -> None:
    rng = np.random.default_rng(2024)
    simulations, sessions, tasks, rate = 200, 25, 4, 0.6
    independent = _coverage(sessions, tasks, np.full((simulations, sessions), rate), rate, rng)
    # Tasks of one session share its world: each session's own rate ~ Beta(3, 2) (mean 0.6).
    correlated = _coverage(sessions, tasks, rng.beta(3.0, 2.0, (simulations, sessions)), rate,
                           rng)
    # 200 simulations: a true 95 % coverage lands in [0.89, 0.99] with ~99 % probability.
    assert 0.89 <= independent <= 0.99, independent
    assert 0.89 <= correlated <= 0.99, correlated


def test_task_level_intervals_would_be_too_narrow_for_correlated_sessions() -> None:
    """Why sessions are resampled whole: treating each task as its own cluster undercovers."""
    rng = np.random.default_rng(7)
    simulations, sessions, tasks, rate = 200, 20, 5, 0.6
    draws = rng.beta(1.2, 0.8, (simulations, sessions))  # strongly correlated within a session
    clustered = _coverage(sessions, tasks, draws, rate, np.random.default_rng(8))
    boot = ClusterBootstrap(sessions * tasks, resamples=400, seed=1)
    hits = 0
    outcomes_rng = np.random.default_rng(8)
    for rates in draws:
        passed = outcomes_rng.binomial(1, np.repeat(rates, tasks))
        estimate, _ = boot.ratio(passed, np.ones(sessions * tasks))
        hits += estimate.low <= rate <= estimate.high
    per_task = hits / simulations
    assert clustered >= 0.88, clustered
    assert per_task < clustered - 0.1, (per_task, clustered)


def test_the_same_seed_gives_the_same_interval_and_differences_are_paired() -> None:
    passed, tasks = np.array([3, 1, 4, 1, 5, 2]), np.full(6, 6)
    one, draws_one = ClusterBootstrap(6, seed=3).ratio(passed, tasks)
    two, draws_two = ClusterBootstrap(6, seed=3).ratio(passed, tasks)
    assert one == two and np.array_equal(draws_one, draws_two)
    assert one.value == pytest.approx(16 / 36) and one.low < one.value < one.high
    # A run that passes exactly one task more in every session: the paired difference is
    # exactly 1/6 in every resample, so its interval has no width.
    boot = ClusterBootstrap(6, seed=3)
    base, base_draws = boot.ratio(passed, tasks)
    better, better_draws = boot.ratio(passed + 1, tasks)
    diff = boot.difference(better.value - base.value, better_draws, base_draws)
    assert diff.value == pytest.approx(1 / 6)
    assert diff.low == pytest.approx(1 / 6) and diff.high == pytest.approx(1 / 6)


def test_bootstrap_refuses_bad_settings() -> None:
    with pytest.raises(ValueError, match="at least one session"):
        ClusterBootstrap(0)
    with pytest.raises(ValueError, match="resamples"):
        ClusterBootstrap(3, resamples=10)
    with pytest.raises(ValueError, match="seed must be a non-negative integer"):
        ClusterBootstrap(3, seed=-1)
    with pytest.raises(ValueError, match="confidence"):
        ClusterBootstrap(3, confidence=1.0)
    with pytest.raises(ValueError, match="one value per session"):
        ClusterBootstrap(3).ratio([1, 2], [3, 3])
