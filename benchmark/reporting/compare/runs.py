"""The runs a comparison reads: results folders or files, one compared run per agent in them,
each with its suite fingerprint; and the check that runs were made on the same tasks.

A run's suite fingerprint is the ``suite_fingerprint`` field its records carry, when they
carry one; otherwise a hash of the set of (session, task) pairs it holds, so two runs of the
same suite have the same fingerprint whatever order, trials or agent they ran with.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from benchmark.running.results import read_task_records

__all__ = [
    "CompareError",
    "Run",
    "TaskKey",
    "align_runs",
    "fingerprint_of",
    "load_runs",
    "runs_of_records",
    "task_fingerprint",
]

TaskKey = tuple[str, str]  # (session, task)
_TEXT_FIELDS = ("session", "task", "family", "level", "category", "template", "agent")


class CompareError(ValueError):
    """Runs that cannot be compared (the message says which and why)."""


@dataclass
class Run:
    """One agent's records from one results file."""

    id: str
    source: Path
    console_run: str  # the id `mavswarm replay` gives the results folder
    agent: str
    records: list[dict[str, Any]] = field(default_factory=list)
    fingerprint: str = ""

    @property
    def task_keys(self) -> set[TaskKey]:
        return {(r["session"], r["task"]) for r in self.records}

    def values(self, name: str) -> list[str]:
        """Distinct non-empty values of an optional record field, as text, sorted."""
        found = {str(r[name]) for r in self.records if r.get(name) not in (None, "", {})}
        return sorted(found)


def task_fingerprint(keys: Iterable[TaskKey]) -> str:
    """sha256 over the sorted (session, task) pairs; the first 16 hex digits."""
    text = "\n".join(f"{session}\t{task}" for session, task in sorted(set(keys)))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def _check_record(path: Path, record: Mapping[str, Any]) -> None:
    where = f"{path}: record {record.get('key')!r}"
    for name in _TEXT_FIELDS:
        value = record.get(name)
        if not isinstance(value, str) or not value:
            raise CompareError(f"{where}: field {name!r} must be a non-empty string, "
                               f"got {value!r}")
    if not isinstance(record.get("passed"), bool):
        raise CompareError(f"{where}: field 'passed' must be a boolean, "
                           f"got {record.get('passed')!r}")
    for name in ("checks_total", "checks_passed", "trial"):
        value = record.get(name, 0 if name == "trial" else None)
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            raise CompareError(f"{where}: field {name!r} must be a non-negative integer, "
                               f"got {value!r}")
    if record["checks_passed"] > record["checks_total"]:
        raise CompareError(f"{where}: 'checks_passed' exceeds 'checks_total'")


def fingerprint_of(run: Run) -> str:
    given = {r.get("suite_fingerprint") for r in run.records}
    if given == {None}:
        return task_fingerprint(run.task_keys)
    if len(given) > 1 or not all(isinstance(g, str) and g for g in given):
        raise CompareError(f"{run.source}: agent {run.agent!r}: records disagree on "
                           f"'suite_fingerprint' ({sorted(map(repr, given))})")
    return str(next(iter(given)))


def _results_file(path: Path) -> tuple[Path, str]:
    """The results file a RUN argument names, and the id the console gives its folder."""
    if path.is_dir():
        file = path / "results.jsonl"
        if not file.is_file():
            raise CompareError(f"{path}: no results.jsonl in this folder")
        return file, path.resolve().name or "run"
    if not path.exists():
        raise CompareError(f"{path}: no such results folder or file")
    return path, path.resolve().parent.name or "run"


def runs_of_records(base: str, source: Path, console_run: str,
                    records: Sequence[dict[str, Any]]) -> list[Run]:
    """One run per agent of one results file's records (checked), agents in name order: id
    `base`, or ``base:agent`` when there are several agents."""
    if not records:
        raise CompareError(f"{source}: the results hold no record")
    by_agent: dict[str, list[dict[str, Any]]] = {}
    for record in records:
        _check_record(source, record)
        by_agent.setdefault(record["agent"], []).append(record)
    runs = []
    for agent in sorted(by_agent):
        run_id = f"{base}:{agent}" if len(by_agent) > 1 else base
        run = Run(run_id, source, console_run, agent, by_agent[agent])
        run.fingerprint = fingerprint_of(run)
        runs.append(run)
    return runs


def load_runs(paths: Sequence[Path]) -> list[Run]:
    """One run per (results file, agent) in argument order, agents in name order. A run's id
    is its folder's name (a file not named results.jsonl: its stem), with ``:agent`` when the
    file holds several agents and ``+`` added until it is unique."""
    runs: list[Run] = []
    seen_files: set[Path] = set()
    taken: set[str] = set()
    console_ids: set[str] = set()
    for path in paths:
        file, console_run = _results_file(Path(path))
        if file.resolve() in seen_files:
            raise CompareError(f"{path}: this results file is given twice")
        seen_files.add(file.resolve())
        while console_run in console_ids:
            console_run += "+"
        console_ids.add(console_run)
        base = console_run if file.name == "results.jsonl" else file.stem
        for run in runs_of_records(base, file, console_run, read_task_records(file)):
            while run.id in taken:
                run.id += "+"
            taken.add(run.id)
            runs.append(run)
    return runs


def _examples(keys: set[TaskKey], limit: int = 3) -> str:
    shown = ", ".join(f"{s}/{t}" for s, t in sorted(keys)[:limit])
    return shown + (", ..." if len(keys) > limit else "")


def align_runs(runs: Sequence[Run], *, intersect: bool) -> tuple[set[TaskKey], list[str]]:
    """The (session, task) pairs every run is compared on, and warnings. Runs on different
    suites or task sets raise CompareError unless `intersect`, which keeps the tasks all of
    them ran and warns what was left out."""
    if len(runs) < 2:
        raise CompareError(f"a comparison needs at least two runs, got {len(runs)}"
                           + (f" ({runs[0].id})" if runs else ""))
    base = runs[0]
    problems: list[str] = []
    for run in runs[1:]:
        if run.fingerprint != base.fingerprint:
            problems.append(f"{run.id} was run on suite {run.fingerprint}, {base.id} on "
                            f"{base.fingerprint}")
        extra, missing = run.task_keys - base.task_keys, base.task_keys - run.task_keys
        if extra or missing:
            problems.append(f"{run.id} has {len(extra)} task(s) {base.id} lacks"
                            f"{f' ({_examples(extra)})' if extra else ''} and lacks "
                            f"{len(missing)} of its tasks"
                            f"{f' ({_examples(missing)})' if missing else ''}")
    common = set.intersection(*(run.task_keys for run in runs))
    if problems and not intersect:
        raise CompareError("the runs were not made on the same tasks: " + "; ".join(problems)
                           + ". Pass --intersect to compare them on the tasks all ran")
    if not common:
        raise CompareError("the runs have no task in common: " + "; ".join(problems))
    warnings = []
    if problems:
        warnings.append("compared on the intersection: " + "; ".join(problems))
        for run in runs:
            left_out = len(run.task_keys - common)
            if left_out:
                warnings.append(f"{run.id}: {left_out} task(s) outside the intersection "
                                "left out")
    return common, warnings
