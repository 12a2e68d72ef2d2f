"""``compare.md``: the comparison as Markdown tables."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from benchmark.reporting.compare.model import CompareReport, Interval, RunSummary, Transitions
from benchmark.scoring.metrics import level_sort_key

__all__ = ["p_value", "pct", "pct_interval", "render_compare_markdown", "signed_interval"]

NA = "n/a"


def pct(rate: float | None) -> str:
    return NA if rate is None else f"{rate * 100:.1f} %"


def pct_interval(interval: Interval) -> str:
    return f"{interval.value * 100:.1f} % [{interval.low * 100:.1f}, {interval.high * 100:.1f}]"


def signed_interval(interval: Interval) -> str:
    return (f"{interval.value * 100:+.1f} pp [{interval.low * 100:+.1f}, "
            f"{interval.high * 100:+.1f}]")


def p_value(p: float) -> str:
    return "1" if p >= 0.9995 else (f"{p:.3f}" if p >= 0.001 else f"{p:.1e}")


def _cell(text: object) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def table(header: Sequence[str], rows: Iterable[Sequence[object]]) -> str:
    lines = ["| " + " | ".join(_cell(h) for h in header) + " |",
             "|" + "|".join(["---"] + ["---:"] * (len(header) - 1)) + "|"]
    lines.extend("| " + " | ".join(_cell(v) for v in row) + " |" for row in rows)
    return "\n".join(lines)


def _listed(values: list[str]) -> str:
    return ", ".join(values) if values else "not recorded"


def _runs_table(runs: Sequence[RunSummary]) -> str:
    return table(("run", "agent", "models", "clock", "link faults", "tasks", "Task Pass",
                  "Avg. Check", "Global Check"),
                 [(r.id, r.agent, _listed(r.models), _listed(r.clocks),
                   ", ".join(r.faults) or "none recorded", r.tasks, pct_interval(r.task_pass_rate),
                   pct_interval(r.average_check), pct_interval(r.global_check)) for r in runs])


def _transition_row(label: str, t: Transitions) -> list[object]:
    return [label, t.pairs, t.fail_to_pass, t.pass_to_fail, t.both_pass, t.both_fail,
            f"{t.pass_rate_change * 100:+.1f} pp", p_value(t.mcnemar_p)]


TRANSITION_HEADER = ("fail->pass", "pass->fail", "both pass", "both fail", "change",
                     "McNemar p")


def _usage_table(runs: Sequence[RunSummary]) -> str:
    def mean(value: float | None, digits: int) -> str:
        return NA if value is None else f"{value:.{digits}f}"
    return table(("run", "token records", "prompt", "completion", "cost (USD)", "sim s",
                  "mean sim s", "wall s", "mean wall s"),
                 [(r.id, r.tokens.records, r.tokens.prompt, r.tokens.completion,
                   f"{r.tokens.cost_usd:.4f}", f"{r.time.sim_time_s:.1f}",
                   mean(r.time.mean_sim_time_s, 1), f"{r.time.wall_time_s:.1f}",
                   mean(r.time.mean_wall_time_s, 2)) for r in runs])


def _side_by_side(runs: Sequence[RunSummary], field: str, column: str) -> str:
    labels: set[str] = set()
    for run in runs:
        labels |= set(getattr(run, field))
    order = sorted(labels, key=level_sort_key if column == "level" else None)
    rows = []
    for label in order:
        row: list[object] = [label]
        for run in runs:
            item = getattr(run, field).get(label)
            row.append(NA if item is None else f"{pct(item.pass_rate)} ({item.passed}/"
                       f"{item.checks if hasattr(item, 'checks') else item.tasks})")
        rows.append(row)
    return table((column, *[r.id for r in runs]), rows)


def render_compare_markdown(report: CompareReport, *, title: str = "mavswarm compare") -> str:
    """The whole Markdown report."""
    boot = report.bootstrap
    parts = [f"# {title}", "",
             f"{len(report.runs)} runs on {report.tasks} tasks in {report.sessions} sessions; "
             f"baseline **{report.baseline}**. Intervals: {boot.confidence * 100:g} % "
             f"bootstrap, {boot.resamples} resamples of whole sessions (seed {boot.seed}): "
             f"{boot.why}. p: exact two-sided McNemar test on the discordant pairs."]
    for warning in report.warnings:
        parts += ["", f"> warning: {warning}"]
    parts += ["", "## Runs", "", _runs_table(report.runs)]
    if report.pairs:
        parts += ["", "## Against the baseline", "",
                  table(("run", "pairs", *TRANSITION_HEADER, "Task Pass diff",
                         "Avg. Check diff", "Global Check diff"),
                        [[*_transition_row(p.run, p.overall),
                          signed_interval(p.task_pass_rate_diff),
                          signed_interval(p.average_check_diff),
                          signed_interval(p.global_check_diff)] for p in report.pairs])]
    for group in ("family", "level", "category", "template"):
        parts += ["", f"## By {group}", "",
                  _side_by_side(report.runs, f"by_{group}", group)]
        for pair in report.pairs:
            rows = [_transition_row(label, t)
                    for label, t in getattr(pair, f"by_{group}").items()]
            parts += ["", f"{pair.run} against {pair.baseline}:", "",
                      table((group, "pairs", *TRANSITION_HEADER), rows)]
    parts += ["", "## Check pass rate by endpoint", "",
              _side_by_side(report.runs, "by_endpoint", "endpoint")]
    hat_k = max(len(r.pass_hat_k) for r in report.runs)
    if hat_k > 1:
        parts += ["", "## pass^k", "",
                  table(("run", *[f"pass^{k}" for k in range(1, hat_k + 1)]),
                        [(r.id, *[pct(r.pass_hat_k.get(str(k)))
                                  for k in range(1, hat_k + 1)]) for r in report.runs])]
    parts += ["", "## Tokens, cost and time", "", _usage_table(report.runs)]
    return "\n".join(parts) + "\n"
