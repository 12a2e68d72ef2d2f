"""The shape of ``compare.json``: pydantic models, from which its JSON Schema is generated
(:func:`compare_schema`). Rates are fractions in 0 .. 1; differences are run minus baseline.
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, Field

__all__ = [
    "COMPARE_SCHEMA_VERSION",
    "BootstrapInfo",
    "ChangedTask",
    "CompareReport",
    "EndpointRate",
    "GroupRate",
    "Interval",
    "PairComparison",
    "RunSummary",
    "TimeTotals",
    "TokenTotals",
    "Transitions",
    "compare_schema",
]

COMPARE_SCHEMA_VERSION = 1


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Interval(_Model):
    """A point estimate and its bootstrap confidence interval."""

    value: float
    low: float
    high: float


class Transitions(_Model):
    """Paired outcomes of the same tasks (and trials) in the baseline and a run."""

    fail_to_pass: int = Field(ge=0, description="failed in the baseline, passed in the run")
    pass_to_fail: int = Field(ge=0, description="passed in the baseline, failed in the run")
    both_pass: int = Field(ge=0)
    both_fail: int = Field(ge=0)
    pairs: int = Field(ge=0, description="paired (session, task, trial) outcomes")
    mcnemar_p: float = Field(ge=0.0, le=1.0,
                             description="exact two-sided McNemar p-value (binomial test of "
                                         "the discordant pairs)")
    pass_rate_change: float = Field(description="(fail_to_pass - pass_to_fail) / pairs")


class ChangedTask(_Model):
    """A paired outcome that changed between the baseline and the run."""

    session: str
    task: str
    trial: int
    family: str
    level: str
    category: str
    template: str
    change: str = Field(pattern="^(fail_to_pass|pass_to_fail)$")


class GroupRate(_Model):
    """A group's task pass rate, with its session-clustered bootstrap interval."""

    tasks: int
    passed: int
    pass_rate: float
    low: float
    high: float


class EndpointRate(_Model):
    checks: int
    passed: int
    pass_rate: float


class TokenTotals(_Model):
    records: int = Field(description="records that report tokens")
    prompt: int
    completion: int
    cost_usd: float


class TimeTotals(_Model):
    sim_time_s: float
    mean_sim_time_s: float | None
    wall_time_s: float
    mean_wall_time_s: float | None


class RunSummary(_Model):
    """One compared run: what it is, and its metrics on the compared tasks."""

    id: str
    source: str = Field(description="the results file")
    console_run: str = Field(description="the run id `mavswarm replay` gives its folder")
    agent: str
    models: list[str] = Field(description="models the records name (empty: not recorded)")
    clocks: list[str]
    faults: list[str] = Field(description="link faults the records name (empty: none "
                                          "recorded)")
    fingerprint: str
    sessions: int
    tasks: int = Field(description="records (task trials) on the compared tasks")
    max_trials: int
    passed_tasks: int
    task_pass_rate: Interval
    average_check: Interval
    global_check: Interval
    total_failed_task_rate: float
    pass_hat_k: dict[str, float | None]
    by_family: dict[str, GroupRate]
    by_level: dict[str, GroupRate]
    by_category: dict[str, GroupRate]
    by_template: dict[str, GroupRate]
    by_endpoint: dict[str, EndpointRate]
    finish: dict[str, int]
    tokens: TokenTotals
    time: TimeTotals


class PairComparison(_Model):
    """A run against the baseline on the paired outcomes both have."""

    baseline: str
    run: str
    overall: Transitions
    by_family: dict[str, Transitions]
    by_level: dict[str, Transitions]
    by_category: dict[str, Transitions]
    by_template: dict[str, Transitions]
    task_pass_rate_diff: Interval
    average_check_diff: Interval
    global_check_diff: Interval
    changed: list[ChangedTask]


class BootstrapInfo(_Model):
    unit: str = Field(description="what is resampled: whole sessions")
    why: str
    resamples: int
    seed: int
    confidence: float


class CompareReport(_Model):
    """Everything ``mavswarm bench compare`` found."""

    schema_version: int = COMPARE_SCHEMA_VERSION
    baseline: str
    fingerprints: list[str]
    intersect: bool
    sessions: int
    tasks: int = Field(description="(session, task) pairs compared")
    warnings: list[str]
    bootstrap: BootstrapInfo
    runs: list[RunSummary]
    pairs: list[PairComparison]


def compare_schema() -> dict[str, Any]:
    """The JSON Schema of ``compare.json``."""
    return CompareReport.model_json_schema()
