"""Benchmark metrics over result records (checks.md section 4), breakdowns and pass^k.

For N evaluated tasks, task i with c_i leaf checks of which p_i pass, and P tasks whose root
check passed:

* Task Pass Rate ``task_pass_rate`` = P / N
* Avg. Check ``average_check_pass_rate`` = (1/N) * sum(p_i / c_i), a task with c_i = 0 adding 0
* Global Check ``check_pass_rate`` = sum(p_i) / sum(c_i)
* Total Failed ``total_failed_task_rate`` = (number of tasks with p_i = 0) / N

Rates are 0.0 over no tasks (or no checks); JSON exports round them to 4 decimals. Records
are first made unique by ``"key"``: the first record with a key wins.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, fields
from typing import Any

__all__ = [
    "BREAKDOWN_FIELDS",
    "FINISH_REASONS",
    "LEVEL_ORDER",
    "Metrics",
    "breakdown",
    "compute_metrics",
    "endpoint_breakdown",
    "finish_sort_key",
    "level_sort_key",
    "pass_hat_k",
    "summarize",
    "unique_records",
]

RATE_DECIMALS = 4
LEVEL_ORDER: tuple[str, ...] = ("easy", "intermediate", "moderate", "hard", "extreme")
FINISH_REASONS: tuple[str, ...] = (
    "finished",
    "tool_call_budget",
    "sim_time_budget",
    "agent_error",
    "task_error",
)
BREAKDOWN_FIELDS: tuple[str, ...] = ("family", "level", "category", "template", "agent")

Record = Mapping[str, Any]


def _rate(numerator: float, denominator: float) -> float:
    return numerator / denominator if denominator else 0.0


def _round(value: float | None) -> float | None:
    return None if value is None else round(value, RATE_DECIMALS)


@dataclass(frozen=True)
class Metrics:
    """Headline metrics of a set of evaluated tasks."""

    tasks: int
    passed_tasks: int
    task_pass_rate: float
    average_check_pass_rate: float
    total_checks: int
    passed_checks: int
    check_pass_rate: float
    total_failed_task_count: int
    total_failed_task_rate: float
    mean_tool_calls: float | None
    mean_sim_time_s: float | None
    mean_wall_time_s: float | None

    def to_json(self) -> dict[str, Any]:
        """The metrics as a JSON-ready dict; rates and means rounded to 4 decimals."""
        out: dict[str, Any] = {}
        for field in fields(self):
            value = getattr(self, field.name)
            out[field.name] = _round(value) if isinstance(value, float) else value
        return out


def _describe(record: Record) -> str:
    key = record.get("key") if isinstance(record, Mapping) else None
    return f"record {key!r}" if key is not None else "record without key"


def _int_field(record: Record, name: str) -> int:
    value = record.get(name)
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ValueError(
            f"{_describe(record)}: field {name!r} must be a non-negative integer, got {value!r}"
        )
    return value


def _str_field(record: Record, name: str) -> str:
    value = record.get(name)
    if not isinstance(value, str) or not value:
        raise ValueError(
            f"{_describe(record)}: field {name!r} must be a non-empty string, got {value!r}"
        )
    return value


def _task_counts(record: Record) -> tuple[bool, int, int]:
    """``(root passed, leaf checks, passing leaf checks)`` of one record, validated."""
    if not isinstance(record, Mapping):
        raise ValueError(f"a results record must be a mapping, got {type(record).__name__}")
    passed = record.get("passed")
    if not isinstance(passed, bool):
        raise ValueError(f"{_describe(record)}: field 'passed' must be a boolean, got {passed!r}")
    total = _int_field(record, "checks_total")
    passing = _int_field(record, "checks_passed")
    if passing > total:
        raise ValueError(
            f"{_describe(record)}: field 'checks_passed' ({passing}) exceeds "
            f"'checks_total' ({total})"
        )
    return passed, total, passing


def _mean_of(records: list[Record], name: str) -> float | None:
    values: list[float] = []
    for record in records:
        value = record.get(name)
        if value is None:
            continue
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not math.isfinite(value)
        ):
            raise ValueError(
                f"{_describe(record)}: field {name!r} must be a finite number or null, "
                f"got {value!r}"
            )
        values.append(float(value))
    return sum(values) / len(values) if values else None


def unique_records(records: Iterable[Record]) -> list[Record]:
    """``records`` in order without repeated keys (the first wins); keyless records all stay."""
    seen: set[str] = set()
    out: list[Record] = []
    for record in records:
        key = record.get("key") if isinstance(record, Mapping) else None
        if isinstance(key, str):
            if key in seen:
                continue
            seen.add(key)
        out.append(record)
    return out


def _metrics_of_unique(records: list[Record]) -> Metrics:
    tasks = len(records)
    passed_tasks = total_checks = passed_checks = failed_tasks = 0
    check_fraction_sum = 0.0
    for record in records:
        passed, total, passing = _task_counts(record)
        passed_tasks += passed
        total_checks += total
        passed_checks += passing
        failed_tasks += passing == 0
        check_fraction_sum += _rate(passing, total)
    return Metrics(
        tasks=tasks,
        passed_tasks=passed_tasks,
        task_pass_rate=_rate(passed_tasks, tasks),
        average_check_pass_rate=_rate(check_fraction_sum, tasks),
        total_checks=total_checks,
        passed_checks=passed_checks,
        check_pass_rate=_rate(passed_checks, total_checks),
        total_failed_task_count=failed_tasks,
        total_failed_task_rate=_rate(failed_tasks, tasks),
        mean_tool_calls=_mean_of(records, "tool_calls"),
        mean_sim_time_s=_mean_of(records, "sim_time_s"),
        mean_wall_time_s=_mean_of(records, "wall_time_s"),
    )


def compute_metrics(records: Iterable[Record]) -> Metrics:
    """Headline metrics of ``records`` exactly as checks.md section 4 defines them."""
    return _metrics_of_unique(unique_records(records))


def level_sort_key(level: str) -> tuple[int, str]:
    """Sort key putting levels in the order easy, intermediate, moderate, hard, extreme."""
    lowered = level.lower()
    if lowered in LEVEL_ORDER:
        return (LEVEL_ORDER.index(lowered), lowered)
    return (len(LEVEL_ORDER), lowered)


def finish_sort_key(reason: str) -> tuple[int, str]:
    """Sort key putting finish reasons in the order of :data:`FINISH_REASONS`."""
    if reason in FINISH_REASONS:
        return (FINISH_REASONS.index(reason), reason)
    return (len(FINISH_REASONS), reason)


def _group(
    records: list[Record], name: str, sort_key: Callable[[str], Any] | None = None
) -> dict[str, list[Record]]:
    groups: dict[str, list[Record]] = {}
    for record in records:
        groups.setdefault(_str_field(record, name), []).append(record)
    return {label: groups[label] for label in sorted(groups, key=sort_key)}


def breakdown(records: Iterable[Record], by: str) -> dict[str, Metrics]:
    """Metrics per value of field ``by`` (family, level, category, template or agent).

    Levels come in difficulty order, other values in alphabetical order.
    """
    if by not in BREAKDOWN_FIELDS:
        raise ValueError(f"breakdown field 'by' must be one of {BREAKDOWN_FIELDS}, got {by!r}")
    sort_key = level_sort_key if by == "level" else None
    groups = _group(unique_records(records), by, sort_key)
    return {label: _metrics_of_unique(group) for label, group in groups.items()}


def endpoint_breakdown(records: Iterable[Record]) -> dict[str, dict[str, Any]]:
    """Leaf-check counts per check endpoint: ``{"checks", "passed", "pass_rate"}``, by name."""
    totals: Counter[str] = Counter()
    passes: Counter[str] = Counter()
    for record in unique_records(records):
        checks = record.get("checks", [])
        if not isinstance(checks, list):
            raise ValueError(f"{_describe(record)}: field 'checks' must be a list, got {checks!r}")
        for index, check in enumerate(checks):
            endpoint = check.get("endpoint") if isinstance(check, Mapping) else None
            if not isinstance(endpoint, str) or not endpoint:
                raise ValueError(
                    f"{_describe(record)}: checks[{index}] field 'endpoint' must be a "
                    f"non-empty string, got {endpoint!r}"
                )
            totals[endpoint] += 1
            passes[endpoint] += check.get("passed") is True
    return {
        endpoint: {
            "checks": totals[endpoint],
            "passed": passes[endpoint],
            "pass_rate": _round(_rate(passes[endpoint], totals[endpoint])),
        }
        for endpoint in sorted(totals)
    }


def _trial_groups(records: list[Record]) -> list[tuple[int, int]]:
    """``(trials, passes)`` per (session, task, agent)."""
    groups: dict[tuple[str, str, str], list[int]] = {}
    for record in records:
        passed, _, _ = _task_counts(record)
        group_key = (
            _str_field(record, "session"),
            _str_field(record, "task"),
            _str_field(record, "agent"),
        )
        counts = groups.setdefault(group_key, [0, 0])
        counts[0] += 1
        counts[1] += passed
    return [(trials, passes) for trials, passes in groups.values()]


def pass_hat_k(records: Iterable[Record], k: int) -> float | None:
    """tau-bench pass^k: mean over tasks with at least k trials of C(c, k) / C(n, k).

    A task is a (session, task, agent) triple with n trials of which c passed. Returns None
    when no task has k trials.
    """
    if isinstance(k, bool) or not isinstance(k, int) or k < 1:
        raise ValueError(f"pass^k parameter 'k' must be a positive integer, got {k!r}")
    ratios = [
        math.comb(passes, k) / math.comb(trials, k)
        for trials, passes in _trial_groups(unique_records(records))
        if trials >= k
    ]
    return sum(ratios) / len(ratios) if ratios else None


def _token_totals(records: list[Record]) -> dict[str, int | float]:
    prompt = completion = counted = 0
    cost_usd = 0.0
    for record in records:
        tokens = record.get("tokens")
        if tokens is None:
            continue
        if not isinstance(tokens, Mapping):
            raise ValueError(
                f"{_describe(record)}: field 'tokens' must be null or an object, got {tokens!r}"
            )
        prompt += _int_field(tokens, "prompt")
        completion += _int_field(tokens, "completion")
        cost = tokens.get("cost_usd", 0.0)
        cost_usd += float(cost) if isinstance(cost, int | float) else 0.0
        counted += 1
    return {"prompt": prompt, "completion": completion, "records": counted,
            "cost_usd": round(cost_usd, 6)}


def _summary_of_unique(records: list[Record]) -> dict[str, Any]:
    groups = _trial_groups(records)
    max_trials = max((trials for trials, _ in groups), default=0)
    finish = Counter(_str_field(record, "finish") for record in records)

    def by(name: str) -> dict[str, Any]:
        sort_key = level_sort_key if name == "level" else None
        return {
            label: _metrics_of_unique(group).to_json()
            for label, group in _group(records, name, sort_key).items()
        }

    return {
        "overall": _metrics_of_unique(records).to_json(),
        "by_family": by("family"),
        "by_level": by("level"),
        "by_category": by("category"),
        "by_template": by("template"),
        "by_endpoint": endpoint_breakdown(records),
        "max_trials": max_trials,
        "pass_hat_k": {str(k): _round(pass_hat_k(records, k)) for k in range(1, max_trials + 1)},
        "finish": {reason: finish[reason] for reason in sorted(finish, key=finish_sort_key)},
        "tokens": _token_totals(records),
    }


def summarize(records: Iterable[Record]) -> dict[str, Any]:
    """Everything above as one JSON-ready dict.

    Keys: ``overall``, ``by_family``, ``by_level`` (difficulty order), ``by_category``,
    ``by_template``, ``by_endpoint``, ``max_trials``, ``pass_hat_k`` (``"1"`` .. max trials),
    ``finish`` (counts per finish reason), ``tokens`` (totals over records that report them),
    ``agents`` (sorted names) and, when there is more than one agent, ``by_agent`` holding
    the same summary for each agent alone.
    """
    unique = unique_records(records)
    summary = _summary_of_unique(unique)
    agent_groups = _group(unique, "agent")
    summary["agents"] = list(agent_groups)
    if len(agent_groups) > 1:
        summary["by_agent"] = {
            agent: _summary_of_unique(group) for agent, group in agent_groups.items()
        }
    return summary
