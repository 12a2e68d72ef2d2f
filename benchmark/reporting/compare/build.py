"""Build a :class:`~benchmark.reporting.compare.model.CompareReport` from runs: per-run metrics with
session-clustered bootstrap intervals, and each run against the baseline (paired
transitions with the exact McNemar test, paired bootstrap differences of the rates)."""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from benchmark.reporting.compare.model import (
    BootstrapInfo,
    ChangedTask,
    CompareReport,
    EndpointRate,
    GroupRate,
    Interval,
    PairComparison,
    RunSummary,
    TimeTotals,
    TokenTotals,
    Transitions,
)
from benchmark.reporting.compare.runs import CompareError, Run, TaskKey, align_runs, load_runs
from benchmark.reporting.compare.stats import (
    DEFAULT_CONFIDENCE,
    DEFAULT_RESAMPLES,
    DEFAULT_SEED,
    ClusterBootstrap,
    Estimate,
    mcnemar_exact_p,
)
from benchmark.scoring.metrics import (
    endpoint_breakdown,
    finish_sort_key,
    level_sort_key,
    pass_hat_k,
)

__all__ = ["GROUPS", "build_compare", "compare_paths", "pick_baseline", "summarize_run"]

GROUPS: tuple[str, ...] = ("family", "level", "category", "template")
WHY_CLUSTERED = ("tasks of one session share its world (drones, targets, obstacles, map), so "
                 "their outcomes are correlated; whole sessions are resampled, the same draws "
                 "for every run, so differences are paired")
Record = Mapping[str, Any]
_DECIMALS = 6


def _r(value: float) -> float:
    return round(float(value), _DECIMALS)


def _interval(estimate: Estimate) -> Interval:
    return Interval(value=_r(estimate.value), low=_r(estimate.low), high=_r(estimate.high))


def _sort_key(name: str) -> Callable[[str], Any] | None:
    return level_sort_key if name == "level" else None


def _grouped(records: Iterable[Record], name: str) -> dict[str, list[Record]]:
    groups: dict[str, list[Record]] = {}
    for record in records:
        groups.setdefault(str(record[name]), []).append(record)
    return {label: groups[label] for label in sorted(groups, key=_sort_key(name))}


def _group_rate(records: Sequence[Record], sessions: Mapping[str, int],
                boot: ClusterBootstrap) -> GroupRate:
    passed, tasks = np.zeros(len(sessions)), np.zeros(len(sessions))
    for r in records:
        tasks[sessions[r["session"]]] += 1
        passed[sessions[r["session"]]] += r["passed"]
    estimate, _ = boot.ratio(passed, tasks)
    return GroupRate(tasks=len(records), passed=int(passed.sum()), pass_rate=_r(estimate.value),
                     low=_r(estimate.low), high=_r(estimate.high))


def _number(record: Record, name: str) -> float | None:
    value = record.get(name)
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value)


def _tokens(records: Sequence[Record]) -> TokenTotals:
    prompt = completion = counted = 0
    cost = 0.0
    for record in records:
        tokens = record.get("tokens")
        if not isinstance(tokens, Mapping):
            continue
        counted += 1
        prompt += int(tokens.get("prompt") or 0)
        completion += int(tokens.get("completion") or 0)
        cost += float(tokens.get("cost_usd") or 0.0)
    return TokenTotals(records=counted, prompt=prompt, completion=completion,
                       cost_usd=round(cost, 6))


def _times(records: Sequence[Record]) -> TimeTotals:
    sim = [v for r in records if (v := _number(r, "sim_time_s")) is not None]
    wall = [v for r in records if (v := _number(r, "wall_time_s")) is not None]
    return TimeTotals(sim_time_s=_r(sum(sim)),
                      mean_sim_time_s=_r(sum(sim) / len(sim)) if sim else None,
                      wall_time_s=_r(sum(wall)),
                      mean_wall_time_s=_r(sum(wall) / len(wall)) if wall else None)


class _Columns:
    """Per-session sums of one run, in the bootstrap's session order."""

    def __init__(self, records: Sequence[Record], sessions: Mapping[str, int]) -> None:
        size = len(sessions)
        self.tasks, self.passed, self.check_share = np.zeros(size), np.zeros(size), np.zeros(size)
        self.checks, self.checks_passed = np.zeros(size), np.zeros(size)
        for r in records:
            s = sessions[r["session"]]
            total, passing = r["checks_total"], r["checks_passed"]
            self.tasks[s] += 1
            self.passed[s] += r["passed"]
            self.check_share[s] += passing / total if total else 0.0
            self.checks[s] += total
            self.checks_passed[s] += passing

    def rates(self, boot: ClusterBootstrap) -> dict[str, tuple[Estimate, np.ndarray]]:
        return {"task_pass_rate": boot.ratio(self.passed, self.tasks),
                "average_check": boot.ratio(self.check_share, self.tasks),
                "global_check": boot.ratio(self.checks_passed, self.checks)}


def _summary(run: Run, records: Sequence[Record], rates: Mapping[str, tuple[Estimate, Any]],
             sessions: Mapping[str, int], boot: ClusterBootstrap) -> RunSummary:
    trials: Counter[TaskKey] = Counter((r["session"], r["task"]) for r in records)
    max_trials = max(trials.values())
    endpoints = endpoint_breakdown(records)
    finish = Counter(str(r.get("finish", "unknown")) for r in records)
    return RunSummary(
        id=run.id, source=str(run.source), console_run=run.console_run, agent=run.agent,
        models=run.values("model"), clocks=run.values("clock"),
        faults=run.values("link_faults"), fingerprint=run.fingerprint,
        sessions=len({r["session"] for r in records}), tasks=len(records),
        max_trials=max_trials, passed_tasks=sum(1 for r in records if r["passed"]),
        task_pass_rate=_interval(rates["task_pass_rate"][0]),
        average_check=_interval(rates["average_check"][0]),
        global_check=_interval(rates["global_check"][0]),
        total_failed_task_rate=_r(sum(1 for r in records if r["checks_passed"] == 0)
                                  / len(records)),
        pass_hat_k={str(k): (None if (v := pass_hat_k(records, k)) is None else _r(v))
                    for k in range(1, max_trials + 1)},
        **{f"by_{name}": {label: _group_rate(group, sessions, boot)
                          for label, group in _grouped(records, name).items()}
           for name in GROUPS},
        by_endpoint={name: EndpointRate(checks=e["checks"], passed=e["passed"],
                                        pass_rate=_r(e["passed"] / e["checks"]))
                     for name, e in endpoints.items()},
        finish={reason: finish[reason] for reason in sorted(finish, key=finish_sort_key)},
        tokens=_tokens(records), time=_times(records))


def _transitions(pairs: Sequence[tuple[Record, Record]]) -> Transitions:
    counts = Counter((a["passed"], b["passed"]) for a, b in pairs)
    up, down = counts[(False, True)], counts[(True, False)]
    return Transitions(fail_to_pass=up, pass_to_fail=down, both_pass=counts[(True, True)],
                       both_fail=counts[(False, False)], pairs=len(pairs),
                       mcnemar_p=mcnemar_exact_p(up, down),
                       pass_rate_change=_r((up - down) / len(pairs)) if pairs else 0.0)


def _trial_key(record: Record) -> tuple[str, str, int]:
    return (record["session"], record["task"], int(record.get("trial", 0)))


def _pair(base: Run, base_records: Sequence[Record], run: Run, records: Sequence[Record],
          base_rates: Mapping[str, tuple[Estimate, Any]],
          rates: Mapping[str, tuple[Estimate, Any]], boot: ClusterBootstrap) -> PairComparison:
    theirs = {_trial_key(r): r for r in records}
    pairs = [(r, theirs[_trial_key(r)]) for r in sorted(base_records, key=_trial_key)
             if _trial_key(r) in theirs]
    changed = [ChangedTask(session=a["session"], task=a["task"], trial=int(a.get("trial", 0)),
                           **{name: a[name] for name in GROUPS},
                           change="fail_to_pass" if b["passed"] else "pass_to_fail")
               for a, b in pairs if a["passed"] != b["passed"]]

    def diff(name: str) -> Interval:
        (mine, my_draws), (their, their_draws) = rates[name], base_rates[name]
        return _interval(boot.difference(mine.value - their.value, my_draws, their_draws))

    by: dict[str, dict[str, Transitions]] = {}
    for name in GROUPS:
        groups: dict[str, list[tuple[Record, Record]]] = {}
        for a, b in pairs:
            groups.setdefault(str(a[name]), []).append((a, b))
        by[f"by_{name}"] = {label: _transitions(groups[label])
                            for label in sorted(groups, key=_sort_key(name))}
    return PairComparison(baseline=base.id, run=run.id, overall=_transitions(pairs), **by,
                          task_pass_rate_diff=diff("task_pass_rate"),
                          average_check_diff=diff("average_check"),
                          global_check_diff=diff("global_check"), changed=changed)


def _file_of(path: Path) -> Path:
    return (path / "results.jsonl" if path.is_dir() else path).resolve()


def pick_baseline(runs: list[Run], baseline: str | None) -> list[Run]:
    """`runs` with the baseline first: the run with that id, or the only run read from that
    path; the first run when `baseline` is None."""
    if baseline is None:
        return runs
    chosen = [r for r in runs if r.id == baseline]
    if not chosen:
        target_file = _file_of(Path(baseline))
        chosen = [r for r in runs if r.source.resolve() == target_file]
        if len(chosen) > 1:
            raise CompareError(f"--baseline {baseline}: that file holds several agents; name "
                               f"one run: {', '.join(r.id for r in chosen)}")
    if not chosen:
        raise CompareError(f"--baseline {baseline!r} is none of the runs compared "
                           f"({', '.join(r.id for r in runs)}) nor one of their files")
    return [chosen[0], *[r for r in runs if r is not chosen[0]]]


def build_compare(runs: Sequence[Run], *, intersect: bool = False,
                  resamples: int = DEFAULT_RESAMPLES, seed: int = DEFAULT_SEED,
                  confidence: float = DEFAULT_CONFIDENCE) -> CompareReport:
    """Compare `runs`, the first being the baseline."""
    common, warnings = align_runs(runs, intersect=intersect)
    kept = [[r for r in run.records if (r["session"], r["task"]) in common] for run in runs]
    session_ids = sorted({session for session, _ in common})
    sessions = {sid: k for k, sid in enumerate(session_ids)}
    if len(session_ids) < 10:
        warnings.append(f"only {len(session_ids)} session(s): the bootstrap resamples whole "
                        "sessions, so with so few the intervals are rough")
    boot = ClusterBootstrap(len(session_ids), resamples=resamples, seed=seed,
                            confidence=confidence)
    rates = [_Columns(records, sessions).rates(boot) for records in kept]
    summaries = [_summary(run, records, rate, sessions, boot)
                 for run, records, rate in zip(runs, kept, rates, strict=True)]
    pairs = [_pair(runs[0], kept[0], run, kept[k], rates[0], rates[k], boot)
             for k, run in enumerate(runs) if k > 0]
    return CompareReport(
        baseline=runs[0].id, fingerprints=sorted({run.fingerprint for run in runs}),
        intersect=intersect, sessions=len(session_ids), tasks=len(common), warnings=warnings,
        bootstrap=BootstrapInfo(unit="session", why=WHY_CLUSTERED, resamples=resamples,
                                seed=seed, confidence=confidence),
        runs=summaries, pairs=pairs)


def summarize_run(run: Run, *, resamples: int = DEFAULT_RESAMPLES,
                  seed: int = DEFAULT_SEED) -> RunSummary:
    """One run alone (a leaderboard row): its metrics with intervals over its own sessions."""
    session_ids = sorted({r["session"] for r in run.records})
    sessions = {sid: k for k, sid in enumerate(session_ids)}
    boot = ClusterBootstrap(len(session_ids), resamples=resamples, seed=seed)
    return _summary(run, run.records, _Columns(run.records, sessions).rates(boot), sessions,
                    boot)


def compare_paths(paths: Sequence[Path], *, baseline: str | None = None,
                  intersect: bool = False, resamples: int = DEFAULT_RESAMPLES,
                  seed: int = DEFAULT_SEED) -> CompareReport:
    """Load the runs at `paths` (folders or files) and compare them; a `baseline` path that
    is none of them is read too, as the baseline."""
    given = [Path(p) for p in paths]
    if (baseline is not None and Path(baseline).exists()
            and _file_of(Path(baseline)) not in {_file_of(p) for p in given}):
        given.insert(0, Path(baseline))
    runs = pick_baseline(load_runs(given), baseline)
    return build_compare(runs, intersect=intersect, resamples=resamples, seed=seed)
