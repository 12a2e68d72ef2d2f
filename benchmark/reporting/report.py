"""Markdown, JSON and HTML reports of a benchmark summary (see
:func:`benchmark.scoring.metrics.summarize`).

Rates are shown as percentages with one decimal. Tables accept a summary straight from
:func:`~benchmark.scoring.metrics.summarize` or one read back from ``report.json``: rows are put in
difficulty order (levels), finish-reason order (finish) or name order (everything else)
whatever order the dict holds them in.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from benchmark.reporting.report_html import DEFAULT_INSPECTOR_URL, render_html
from benchmark.scoring.metrics import finish_sort_key, level_sort_key, summarize

__all__ = ["metrics_table", "render_markdown", "write_report", "write_text_atomic"]

MISSING = "n/a"
_GROUP_SECTIONS: tuple[tuple[str, str, str], ...] = (
    ("by_family", "By family", "family"),
    ("by_level", "By level", "level"),
    ("by_category", "By category", "category"),
    ("by_template", "By template", "template"),
)
_GROUP_HEADER: tuple[str, ...] = (
    "tasks",
    "passed",
    "Task Pass",
    "Avg. Check",
    "Global Check",
    "Total Failed",
    "mean tool calls",
    "mean sim time (s)",
)


def _percent(rate: float | None) -> str:
    return MISSING if rate is None else f"{rate * 100:.1f} %"


def _number(value: float | None, decimals: int = 1) -> str:
    return MISSING if value is None else f"{value:.{decimals}f}"


def _cell(text: object) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _table(header: Sequence[str], rows: Iterable[Sequence[object]]) -> str:
    lines = [
        "| " + " | ".join(_cell(name) for name in header) + " |",
        "|" + "|".join(["---"] + ["---:"] * (len(header) - 1)) + "|",
    ]
    lines.extend("| " + " | ".join(_cell(value) for value in row) + " |" for row in rows)
    return "\n".join(lines)


def _overall(summary: Mapping[str, Any]) -> Mapping[str, Any]:
    overall = summary.get("overall") if isinstance(summary, Mapping) else None
    if not isinstance(overall, Mapping):
        raise ValueError(f"summary field 'overall' must be a metrics object, got {overall!r}")
    return overall


def _headline_rows(metrics: Mapping[str, Any]) -> list[tuple[str, str, str]]:
    tasks = metrics["tasks"]
    return [
        (
            "Task Pass Rate",
            _percent(metrics["task_pass_rate"]),
            f"{metrics['passed_tasks']} / {tasks} tasks",
        ),
        (
            "Avg. Check",
            _percent(metrics["average_check_pass_rate"]),
            f"mean over {tasks} tasks",
        ),
        (
            "Global Check",
            _percent(metrics["check_pass_rate"]),
            f"{metrics['passed_checks']} / {metrics['total_checks']} checks",
        ),
        (
            "Total Failed",
            _percent(metrics["total_failed_task_rate"]),
            f"{metrics['total_failed_task_count']} / {tasks} tasks",
        ),
    ]


def metrics_table(summary: Mapping[str, Any]) -> str:
    """The headline table alone: Task Pass Rate, Avg. Check, Global Check, Total Failed."""
    return _table(("Metric", "Value", "Count"), _headline_rows(_overall(summary)))


def _group_row(label: str, metrics: Mapping[str, Any]) -> list[object]:
    return [
        label,
        metrics["tasks"],
        metrics["passed_tasks"],
        _percent(metrics["task_pass_rate"]),
        _percent(metrics["average_check_pass_rate"]),
        _percent(metrics["check_pass_rate"]),
        _percent(metrics["total_failed_task_rate"]),
        _number(metrics.get("mean_tool_calls")),
        _number(metrics.get("mean_sim_time_s")),
    ]


def _group_table(column: str, groups: Mapping[str, Mapping[str, Any]]) -> str:
    sort_key: Callable[[str], Any] | None = level_sort_key if column == "level" else None
    rows = [_group_row(label, groups[label]) for label in sorted(groups, key=sort_key)]
    return _table((column, *_GROUP_HEADER), rows)


def _endpoint_table(endpoints: Mapping[str, Mapping[str, Any]]) -> str:
    rows = [
        (name, item["checks"], item["passed"], _percent(item["pass_rate"]))
        for name, item in ((name, endpoints[name]) for name in sorted(endpoints))
    ]
    return _table(("endpoint", "checks", "passed", "pass rate"), rows)


def _pass_hat_k_table(values: Mapping[str, float | None]) -> str:
    rows = [(f"pass^{k}", _percent(values[k])) for k in sorted(values, key=int)]
    return _table(("k", "value"), rows)


def _finish_table(finish: Mapping[str, int]) -> str:
    total = sum(finish.values())
    rows = [
        (reason, finish[reason], _percent(finish[reason] / total if total else None))
        for reason in sorted(finish, key=finish_sort_key)
    ]
    return _table(("finish", "tasks", "share"), rows)


def _agent_table(by_agent: Mapping[str, Mapping[str, Any]]) -> str:
    rows = [_group_row(agent, _overall(by_agent[agent])) for agent in sorted(by_agent)]
    return _table(("agent", *_GROUP_HEADER), rows)


def render_markdown(summary: Mapping[str, Any], *, title: str = "mavswarm benchmark") -> str:
    """A Markdown report: headline table, then per-group, endpoint, pass^k and finish tables."""
    parts = [f"# {title}", "", metrics_table(summary)]
    by_agent = summary.get("by_agent")
    if isinstance(by_agent, Mapping) and by_agent:
        parts += ["", "## By agent", "", _agent_table(by_agent)]
    for key, heading, column in _GROUP_SECTIONS:
        groups = summary.get(key)
        if isinstance(groups, Mapping) and groups:
            parts += ["", f"## {heading}", "", _group_table(column, groups)]
    endpoints = summary.get("by_endpoint")
    if isinstance(endpoints, Mapping) and endpoints:
        parts += ["", "## By check endpoint", "", _endpoint_table(endpoints)]
    hat_k = summary.get("pass_hat_k")
    if isinstance(hat_k, Mapping) and hat_k:
        parts += ["", "## pass^k", "", _pass_hat_k_table(hat_k)]
    finish = summary.get("finish")
    if isinstance(finish, Mapping) and finish:
        parts += ["", "## Finish reasons", "", _finish_table(finish)]
    tokens = summary.get("tokens")
    if isinstance(tokens, Mapping) and tokens.get("records"):
        parts += [
            "",
            "## Tokens",
            "",
            _table(
                ("records", "prompt", "completion", "cost (USD)"),
                [(tokens["records"], tokens["prompt"], tokens["completion"],
                  f"{float(tokens.get('cost_usd', 0.0)):.4f}")],
            ),
        ]
    return "\n".join(parts) + "\n"


def write_text_atomic(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file, so readers never see half of it."""
    fd, temp_name = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        os.fchmod(fd, 0o644)
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
        os.replace(temp_name, path)
    except BaseException:
        Path(temp_name).unlink(missing_ok=True)
        raise


def write_report(
    records: Iterable[Mapping[str, Any]],
    out_dir: str | Path,
    *,
    title: str = "mavswarm benchmark",
    inspector_url: str = DEFAULT_INSPECTOR_URL,
    results_dir: str | Path | None = None,
    run_id: str | None = None,
) -> tuple[Path, Path, Path]:
    """Write ``report.md``, ``report.json`` (sorted keys, 2-space indent) and ``report.html``
    (:mod:`benchmark.reporting.report_html`, its task links into the inspector at
    `inspector_url`, which
    ``mavswarm replay RESULTS_DIR`` serves for `results_dir`, default `out_dir`; with `run_id`
    each link names the run) into ``out_dir``.

    Returns the paths of the Markdown, JSON and HTML files.
    """
    rows = list(records)
    directory = Path(out_dir)
    summary = summarize(rows)
    page = render_html(rows, title=title, inspector_url=inspector_url,
                       results_dir=str(results_dir if results_dir is not None else directory),
                       run_id=run_id)
    directory.mkdir(parents=True, exist_ok=True)
    md_path = directory / "report.md"
    json_path = directory / "report.json"
    html_path = directory / "report.html"
    write_text_atomic(json_path, json.dumps(summary, sort_keys=True, indent=2) + "\n")
    write_text_atomic(md_path, render_markdown(summary, title=title))
    write_text_atomic(html_path, page)
    return md_path, json_path, html_path
