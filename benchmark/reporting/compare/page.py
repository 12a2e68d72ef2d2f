"""``compare.html``: one self-contained page (inline CSS and SVG, no script) of a comparison:
the runs with their intervals, paired-transition bars, pass rate against difficulty per run,
per-family paired changes, the category, level, template and endpoint tables, pass^k, usage,
and every changed task linked to both runs' inspector pages."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from html import escape

from benchmark.reporting.compare.charts import (
    Change,
    Series,
    Span,
    category_lines,
    diverging_bars,
    interval_rows,
    series_color,
)
from benchmark.reporting.compare.markdown import p_value, pct, pct_interval, signed_interval
from benchmark.reporting.compare.model import CompareReport, PairComparison, RunSummary, Transitions
from benchmark.reporting.inspector_links import (
    DEFAULT_INSPECTOR_URL,
    check_inspector_url,
    inspector_link,
)
from benchmark.reporting.report_html import PAGE_CSS
from benchmark.scoring.metrics import LEVEL_ORDER, level_sort_key

__all__ = ["render_compare_html"]

_EXTRA_CSS = """
td.up { color: #2a9d5c; font-weight: 600; } td.down { color: #d1495b; font-weight: 600; }
td.sig { background: #fff3c4; }
.swatch { display: inline-block; width: 10px; height: 10px; border-radius: 2px;
  margin-right: 6px; }
"""


def _panel(ident: str, title: str, body: str, note: str = "") -> str:
    note_html = f'<p class="note">{escape(note)}</p>' if note else ""
    return (f'<section class="panel" id="{ident}"><h2>{escape(title)}</h2>{note_html}{body}'
            "</section>")


def _table(head: Sequence[str], rows: Sequence[Sequence[str]], *, ident: str = "",
           numeric_from: int = 1) -> str:
    """`rows` are HTML cells' inner text (already escaped) or full ``<td>`` elements."""
    def th(k: int, h: str) -> str:
        return f'<th class="num">{escape(h)}</th>' if k >= numeric_from else \
            f"<th>{escape(h)}</th>"

    def td(k: int, cell: str) -> str:
        if cell.startswith("<td"):
            return cell
        return f'<td class="num">{cell}</td>' if k >= numeric_from else f"<td>{cell}</td>"

    anchor = f' id="{ident}"' if ident else ""
    return (f"<table{anchor}><thead><tr>{''.join(th(k, h) for k, h in enumerate(head))}</tr>"
            "</thead><tbody>"
            + "".join("<tr>" + "".join(td(k, c) for k, c in enumerate(row)) + "</tr>"
                      for row in rows) + "</tbody></table>")


def _swatch(k: int, name: str) -> str:
    return f'<span class="swatch" style="background:{series_color(k)}"></span>{escape(name)}'


def _runs_table(report: CompareReport) -> str:
    rows = [[_swatch(k, r.id) + (" (baseline)" if r.id == report.baseline else ""),
             escape(r.agent), escape(", ".join(r.models) or "not recorded"),
             escape(", ".join(r.clocks) or "not recorded"),
             escape(", ".join(r.faults) or "none recorded"), str(r.tasks),
             escape(pct_interval(r.task_pass_rate)), escape(pct_interval(r.average_check)),
             escape(pct_interval(r.global_check)), escape(pct(r.total_failed_task_rate))]
            for k, r in enumerate(report.runs)]
    return _table(("run", "agent", "models", "clock", "link faults", "tasks", "Task Pass",
                   "Avg. Check", "Global Check", "Total Failed"), rows, numeric_from=5)


def _intervals(report: CompareReport) -> str:
    spans = [Span(r.id, r.task_pass_rate.value, r.task_pass_rate.low, r.task_pass_rate.high,
                  series_color(k), f"{pct_interval(r.task_pass_rate)}")
             for k, r in enumerate(report.runs)]
    chart = interval_rows(spans, label="Task pass rate per run with its interval")
    if not report.pairs:
        return chart
    diffs = [Span(f"{p.run} \u2212 {p.baseline}", p.task_pass_rate_diff.value,
                  p.task_pass_rate_diff.low, p.task_pass_rate_diff.high, series_color(k + 1),
                  signed_interval(p.task_pass_rate_diff)) for k, p in enumerate(report.pairs)]
    bound = max(0.05, *(max(abs(d.low), abs(d.high)) for d in diffs))
    bound = min(1.0, round(bound + 0.05, 1))
    return chart + "<h3>Difference from the baseline (paired)</h3>" + interval_rows(
        diffs, label="Task pass rate difference from the baseline", lo=-bound, hi=bound,
        signed=True)


def _transition_cells(t: Transitions) -> list[str]:
    sig = ' class="num sig"' if t.mcnemar_p < 0.05 else ' class="num"'
    return [str(t.pairs), f'<td class="num up">{t.fail_to_pass}</td>',
            f'<td class="num down">{t.pass_to_fail}</td>', str(t.both_pass), str(t.both_fail),
            escape(f"{t.pass_rate_change * 100:+.1f} pp"), f"<td{sig}>{p_value(t.mcnemar_p)}</td>"]


_TRANSITION_HEAD = ("pairs", "fail\u2192pass", "pass\u2192fail", "both pass", "both fail",
                    "change", "McNemar p")


def _transitions(report: CompareReport) -> str:
    rows = [Change(p.run, p.overall.fail_to_pass, p.overall.pass_to_fail,
                   f"p = {p_value(p.overall.mcnemar_p)}") for p in report.pairs]
    chart = diverging_bars(rows, label="Paired transitions against the baseline")
    table = _table(("run", *_TRANSITION_HEAD),
                   [[escape(p.run), *_transition_cells(p.overall)] for p in report.pairs])
    return chart + table


def _difficulty(report: CompareReport) -> str:
    seen = {level for r in report.runs for level in r.by_level}
    levels = [lv for lv in LEVEL_ORDER if lv in seen] + sorted(
        (lv for lv in seen if lv not in LEVEL_ORDER), key=level_sort_key)
    def column(run: RunSummary, name: str) -> list[float | None]:
        return [getattr(run.by_level[lv], name) if lv in run.by_level else None
                for lv in levels]

    series = [Series(r.id, series_color(k), column(r, "pass_rate"), column(r, "low"),
                     column(r, "high")) for k, r in enumerate(report.runs)]
    return category_lines(levels, series, label="Task pass rate against difficulty per run",
                          x_label="difficulty level", y_label="task pass rate")


def _family_changes(pair: PairComparison) -> str:
    rows = [Change(family, t.fail_to_pass, t.pass_to_fail,
                   f"{t.pairs} pairs, p = {p_value(t.mcnemar_p)}")
            for family, t in pair.by_family.items()]
    return (f"<h3>{escape(pair.run)} against {escape(pair.baseline)}</h3>"
            + diverging_bars(rows, label=f"Paired changes by family: {pair.run}"))


def _group_table(report: CompareReport, group: str, ident: str) -> str:
    labels: set[str] = set()
    for run in report.runs:
        labels |= set(getattr(run, f"by_{group}"))
    order = sorted(labels, key=level_sort_key if group == "level" else None)
    head = [group, *[f"{r.id} pass" for r in report.runs]]
    for pair in report.pairs:
        head += [f"{pair.run}: f\u2192p", "p\u2192f", "p"]
    rows = []
    for label in order:
        row = [escape(label)]
        for run in report.runs:
            item = getattr(run, f"by_{group}").get(label)
            row.append("n/a" if item is None else
                       f'<td class="num" title="interval {item.low * 100:.1f} to '
                       f'{item.high * 100:.1f} %">'
                       + escape(f"{pct(item.pass_rate)} ({item.passed}/{item.tasks})")
                       + "</td>")
        for pair in report.pairs:
            t = getattr(pair, f"by_{group}").get(label)
            cells = _transition_cells(t) if t is not None else []
            row += [cells[1], cells[2], cells[6]] if cells else ["-", "-", "-"]
        rows.append(row)
    return _table(head, rows, ident=ident)


def _endpoint_table(report: CompareReport) -> str:
    names = sorted({name for r in report.runs for name in r.by_endpoint})
    base = report.runs[0]
    head = ["endpoint", *[r.id for r in report.runs],
            *[f"{r.id} \u2212 {base.id}" for r in report.runs[1:]]]
    rows = []
    for name in names:
        row = [f"<code>{escape(name)}</code>"]
        for run in report.runs:
            e = run.by_endpoint.get(name)
            row.append("n/a" if e is None else
                       escape(f"{pct(e.pass_rate)} ({e.passed}/{e.checks})"))
        b = base.by_endpoint.get(name)
        for run in report.runs[1:]:
            e = run.by_endpoint.get(name)
            if e is None or b is None:
                row.append("n/a")
                continue
            delta = e.pass_rate - b.pass_rate
            kind = "up" if delta > 0 else "down" if delta < 0 else "num"
            row.append(f'<td class="num {kind}">{delta * 100:+.1f} pp</td>')
        rows.append(row)
    return _table(head, rows, ident="endpoint-table")


def _pass_hat_k(report: CompareReport) -> str:
    k_max = max(len(r.pass_hat_k) for r in report.runs)
    rows = [[escape(r.id), *[escape(pct(r.pass_hat_k.get(str(k)))) for k in range(1, k_max + 1)]]
            for r in report.runs]
    return _table(("run", *[f"pass^{k}" for k in range(1, k_max + 1)]), rows)


def _usage(report: CompareReport) -> str:
    def num(value: float | None, digits: int) -> str:
        return "n/a" if value is None else f"{value:,.{digits}f}"
    rows = [[escape(r.id), str(r.tokens.records), f"{r.tokens.prompt:,}",
             f"{r.tokens.completion:,}", f"{r.tokens.cost_usd:.4f}",
             num(r.time.sim_time_s, 1), num(r.time.mean_sim_time_s, 1),
             num(r.time.wall_time_s, 1), num(r.time.mean_wall_time_s, 2)]
            for r in report.runs]
    return _table(("run", "token records", "prompt", "completion", "cost (USD)", "sim s",
                   "mean sim s", "wall s", "mean wall s"), rows)


_CHANGE_CELLS = {"fail_to_pass": '<td class="up">fail\u2192pass</td>',
                 "pass_to_fail": '<td class="down">pass\u2192fail</td>'}


def _changed(report: CompareReport, link: Callable[[RunSummary, str, str, int], str]) -> str:
    by_id = {r.id: r for r in report.runs}
    parts = []
    for pair in report.pairs:
        base, run = by_id[pair.baseline], by_id[pair.run]
        rows = [[escape(f"{c.session} / {c.task}"), str(c.trial), escape(c.family),
                 escape(c.level), escape(c.template),
                 _CHANGE_CELLS[c.change],
                 f'<td><a href="{escape(link(base, c.session, c.task, c.trial))}" '
                 f'target="_blank">{escape(base.id)}</a> \u00b7 '
                 f'<a href="{escape(link(run, c.session, c.task, c.trial))}" '
                 f'target="_blank">{escape(run.id)}</a></td>'] for c in pair.changed]
        parts.append(f"<details><summary>{escape(pair.run)} against {escape(pair.baseline)}: "
                     f"{len(pair.changed)} changed</summary>"
                     + _table(("task", "trial", "family", "level", "template", "change",
                               "inspect"), rows, numeric_from=99) + "</details>")
    return "".join(parts)


def render_compare_html(report: CompareReport, *, title: str = "mavswarm compare",
                        inspector_url: str = DEFAULT_INSPECTOR_URL,
                        serve_hint: str = "RESULTS_DIR ...") -> str:
    """The whole page."""
    base_url = check_inspector_url(inspector_url)

    def link(run: RunSummary, session: str, task: str, trial: int) -> str:
        return inspector_link(base_url, session, task, trial, run=run.console_run,
                              agent=run.agent)

    boot = report.bootstrap
    parts = [f"<h1>{escape(title)}</h1>",
             f'<p class="sub">{len(report.runs)} runs on {report.tasks} tasks in '
             f"{report.sessions} sessions; baseline <b>{escape(report.baseline)}</b>. "
             f"Intervals: {boot.confidence * 100:g} % percentile bootstrap, {boot.resamples} "
             f"resamples of whole sessions (seed {boot.seed}): {escape(boot.why)}. p: exact "
             "two-sided McNemar test on the discordant pairs (highlighted below 0.05).</p>",
             f'<p class="hint">Changed tasks link into the inspector at '
             f"<code>{escape(base_url)}</code>, each to its own run's page. Start it first: "
             f"<code>mavswarm replay {escape(serve_hint)}</code>.</p>"]
    parts += [f'<p class="hint warning">warning: {escape(w)}</p>' for w in report.warnings]
    parts.append(_panel("runs", "Runs", _runs_table(report)))
    parts.append(_panel("intervals", "Task pass rate with intervals", _intervals(report)))
    if report.pairs:
        parts.append(_panel("transitions", "Paired transitions against the baseline",
                            _transitions(report), "The same task and trial in both runs: "
                            "gains (failed in the baseline, passed in the run) right, losses "
                            "left."))
    parts.append(_panel("difficulty", "Pass rate against difficulty", _difficulty(report)))
    if report.pairs:
        parts.append(_panel("families", "Paired changes by family",
                            "".join(_family_changes(p) for p in report.pairs)))
    parts.append(_panel("categories", "By category",
                        _group_table(report, "category", "category-table")))
    parts.append(_panel("levels", "By level", _group_table(report, "level", "level-table")))
    parts.append(_panel("templates", "By template",
                        "<details><summary>every template</summary>"
                        + _group_table(report, "template", "template-table") + "</details>"))
    parts.append(_panel("endpoints", "Check pass rate by endpoint", _endpoint_table(report),
                        "Leaf checks of each validation endpoint that passed, side by side."))
    if max(len(r.pass_hat_k) for r in report.runs) > 1:
        parts.append(_panel("passk", "pass^k", _pass_hat_k(report),
                            "Chance that k trials of a task all pass."))
    parts.append(_panel("usage", "Tokens, cost and time", _usage(report)))
    if report.pairs:
        parts.append(_panel("changed", "Changed tasks", _changed(report, link)))
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            '<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<title>{escape(title)}</title><style>{PAGE_CSS}{_EXTRA_CSS}</style></head>"
            f"<body><main>{''.join(parts)}</main></body></html>\n")
