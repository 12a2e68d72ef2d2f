"""``report.html``: one self-contained page of charts and tables over result records.

Everything is inline (CSS and SVG written here): the page opens from disk with no network
and no other file. Charts: pass rate by family x level (a heatmap), by category, by agent
and by check endpoint, pass^k against k, tokens and cost per task, simulated against wall
time per task. Tables: every failed task with its failing check leaves (measured value
against threshold), and every task. Each task links into the inspector that
``mavswarm replay RESULTS_DIR`` serves:
``{base}/inspect/{session}/{task}?run={run}&agent={agent}&trial={k}``, the run being the id
the replay server gives the results folder (its name), so it opens that run's page even when
several runs are served.
"""

from __future__ import annotations

import statistics
from collections.abc import Iterable, Mapping, Sequence
from html import escape
from typing import Any

from benchmark.reporting.charts import (
    FAIL_COLOR,
    PASS_COLOR,
    Bar,
    Point,
    bar_strip,
    hbars,
    heatmap,
    line_chart,
    scatter,
)
from benchmark.reporting.inspector_links import (
    DEFAULT_INSPECTOR_URL,
    TaskLinks,
    check_inspector_url,
    inspector_link,
)
from benchmark.scoring.failed_checks import failed_leaves
from benchmark.scoring.metrics import compute_metrics, finish_sort_key, level_sort_key, summarize
from benchmark.scoring.metrics import unique_records as unique

__all__ = [
    "DEFAULT_INSPECTOR_URL",
    "PAGE_CSS",
    "check_inspector_url",
    "inspector_link",
    "render_html",
    "run_facts",
]

ALL = "all"
Record = Mapping[str, Any]

PAGE_CSS = """
:root { color-scheme: light; }
* { box-sizing: border-box; }
body { margin: 0; background: #f4f6f9; color: #1f2933;
  font: 14px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; }
main { max-width: 1240px; margin: 0 auto; padding: 28px 24px 60px; }
h1 { font-size: 26px; margin: 0 0 4px; }
h2 { font-size: 17px; margin: 0 0 4px; }
h3 { font-size: 14px; margin: 14px 0 2px; color: #3d4654; }
p.sub, p.hint, .panel p.note { color: #66707f; margin: 0 0 12px; }
p.hint { background: #fff8e6; border: 1px solid #f2dca0; border-radius: 8px;
  padding: 10px 14px; color: #5a4a1a; }
code { background: #eef0f4; border-radius: 4px; padding: 1px 5px; font-size: 12.5px; }
.cards { display: grid; grid-template-columns: repeat(auto-fit, minmax(170px, 1fr));
  gap: 12px; margin: 18px 0; }
.card { background: #fff; border-radius: 10px; padding: 14px 16px;
  box-shadow: 0 1px 2px rgba(16, 24, 40, .08); }
.card .label { color: #66707f; font-size: 12px; text-transform: uppercase;
  letter-spacing: .04em; }
.card .value { font-size: 28px; font-weight: 700; margin-top: 2px; }
.card .count { color: #66707f; font-size: 12.5px; }
.grid { display: grid; grid-template-columns: 1fr 1fr; gap: 16px; }
@media (max-width: 900px) { .grid { grid-template-columns: 1fr; } }
.panel { background: #fff; border-radius: 10px; padding: 18px 20px; margin: 16px 0;
  box-shadow: 0 1px 2px rgba(16, 24, 40, .08); }
.grid .panel { margin: 0; }
svg.chart { width: 100%; height: auto; display: block; }
svg.chart a:hover rect, svg.chart a:hover circle { stroke: #1f2933; stroke-width: 1.5; }
table { border-collapse: collapse; width: 100%; font-size: 13px; }
th, td { text-align: left; padding: 6px 8px; border-bottom: 1px solid #e6e9ef;
  vertical-align: top; }
th { color: #66707f; font-weight: 600; background: #fafbfc; position: sticky; top: 0; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; }
.pass { color: #2a9d5c; font-weight: 600; }
.fail { color: #d1495b; font-weight: 600; }
ul.leaves { margin: 0; padding-left: 16px; }
ul.leaves li { margin-bottom: 4px; }
.leaf-condition { color: #66707f; font-size: 12px; }
.measured { font-weight: 600; color: #d1495b; }
.threshold { font-weight: 600; }
details summary { cursor: pointer; font-weight: 600; }
a { color: #2f5fc4; }
"""


def _pct(rate: float | None) -> str:
    return "n/a" if rate is None else f"{rate * 100:.1f} %"


def _num(value: Any, decimals: int = 1) -> str:
    return f"{value:,.{decimals}f}" if isinstance(value, int | float) else "n/a"


def _duration(seconds: float) -> str:
    if seconds < 120.0:
        return f"{seconds:.0f} s"
    if seconds < 7200.0:
        return f"{seconds / 60.0:.1f} min"
    return f"{seconds / 3600.0:.1f} h"


def _cards(overall: Mapping[str, Any], records: Sequence[Record]) -> str:
    tasks = overall["tasks"]
    sim = [r["sim_time_s"] for r in records if isinstance(r.get("sim_time_s"), int | float)]
    cards = [
        ("Task Pass Rate", _pct(overall["task_pass_rate"]),
         f"{overall['passed_tasks']} / {tasks} tasks"),
        ("Avg. Check", _pct(overall["average_check_pass_rate"]), f"mean over {tasks} tasks"),
        ("Global Check", _pct(overall["check_pass_rate"]),
         f"{overall['passed_checks']} / {overall['total_checks']} checks"),
        ("Total Failed", _pct(overall["total_failed_task_rate"]),
         f"{overall['total_failed_task_count']} / {tasks} tasks pass no check"),
        ("Simulated time", _duration(sum(sim)),
         f"mean {_num(overall.get('mean_sim_time_s'))} s per task"),
    ]
    return '<section class="cards">' + "".join(
        f'<div class="card"><div class="label">{escape(label)}</div>'
        f'<div class="value">{escape(value)}</div><div class="count">{escape(count)}</div>'
        f"</div>" for label, value, count in cards) + "</section>"


def _panel(title: str, body: str, note: str = "", *, ident: str = "") -> str:
    anchor = f' id="{escape(ident)}"' if ident else ""
    note_html = f'<p class="note">{note}</p>' if note else ""
    return f'<section class="panel"{anchor}><h2>{escape(title)}</h2>{note_html}{body}</section>'


def _family_level_heatmap(records: Sequence[Record]) -> str:
    families = sorted({str(r["family"]) for r in records})
    levels = sorted({str(r["level"]) for r in records}, key=level_sort_key)
    groups: dict[tuple[str, str], list[Record]] = {}
    for r in records:
        for row in (str(r["family"]), ALL):
            for col in (str(r["level"]), ALL):
                groups.setdefault((row, col), []).append(r)
    cells = {}
    for key, group in groups.items():
        m = compute_metrics(group)
        cells[key] = (m.task_pass_rate, f"{m.passed_tasks} / {m.tasks} tasks")
    rows = [*families, ALL] if len(families) > 1 else families
    cols = [*levels, ALL] if len(levels) > 1 else levels
    return heatmap(rows, cols, cells, label="Task pass rate by family and level",
                   summary_row=ALL, summary_col=ALL)


def _group_bars(groups: Mapping[str, Mapping[str, Any]]) -> list[Bar]:
    return [Bar(name, m["task_pass_rate"], f"{m['passed_tasks']} / {m['tasks']}")
            for name, m in sorted(groups.items())]


def _endpoint_bars(endpoints: Mapping[str, Mapping[str, Any]]) -> list[Bar]:
    items = sorted(endpoints.items(), key=lambda kv: (kv[1]["pass_rate"], kv[0]))
    return [Bar(name, e["pass_rate"], f"{e['passed']} / {e['checks']} checks")
            for name, e in items]


def _pass_hat_k(summary: Mapping[str, Any]) -> str:
    points = [(int(k), v) for k, v in sorted(summary["pass_hat_k"].items(), key=lambda kv:
                                             int(kv[0])) if v is not None]
    if not points:
        return '<p class="note">No task has a trial.</p>'
    chart = line_chart(points, label="pass^k against k", x_label="k (trials that must all "
                       "pass)", y_label="pass^k")
    if len(points) == 1:
        chart += ('<p class="note">One trial per task: run with <code>--trials K</code> to '
                  "see how reliably tasks pass again.</p>")
    return chart


def _task_title(r: Record) -> str:
    verdict = "pass" if r["passed"] else "fail"
    return (f"{r['session']} {r['task']} ({r['template']}), trial {r.get('trial', 0)}: "
            f"{verdict}, {r['checks_passed']}/{r['checks_total']} checks")


def _tokens(records: Sequence[Record], base: TaskLinks) -> str:
    rows = [r for r in records if isinstance(r.get("tokens"), Mapping)]
    if not rows:
        return _panel("Tokens and cost per task", "", "No record reports tokens: this agent "
                      "uses no model (the oracle and noop agents).", ident="tokens")
    token_bars = []
    cost_bars = []
    for r in rows:
        t = r["tokens"]
        prompt, completion = int(t.get("prompt", 0)), int(t.get("completion", 0))
        cost = float(t.get("cost_usd", 0.0) or 0.0)
        title = _task_title(r)
        token_bars.append(((prompt, completion), f"{title}; {prompt:,} prompt + "
                           f"{completion:,} completion tokens", base.of(r)))
        cost_bars.append(((cost,), f"{title}; ${cost:.4f}", base.of(r)))
    totals = [sum(parts) for parts, _, _ in token_bars]
    costs = [parts[0] for parts, _, _ in cost_bars]
    note = (f"{len(rows)} tasks report tokens: median {statistics.median(totals):,.0f}, "
            f"max {max(totals):,} tokens per task; cost {sum(costs):.4f} USD in all, "
            f"{sum(costs) / len(costs):.4f} USD per task on average.")
    left = bar_strip(token_bars, label="Tokens per task", colors=("#3b6fd8", "#f4a259"),
                     series=("prompt", "completion"))
    if any(costs):
        right = bar_strip(cost_bars, label="Cost per task", colors=("#7b61c9",),
                          series=("cost (USD)",), y_unit=" $", decimals=4)
    else:
        right = ('<p class="note">No price was given (<code>--price-in</code>, '
                 "<code>--price-out</code>): every task cost 0 USD.</p>")
    return _panel("Tokens and cost per task", f'<div class="grid"><div>{left}</div>'
                  f"<div>{right}</div></div>", escape(note), ident="tokens")


def _times(records: Sequence[Record], base: TaskLinks) -> str:
    points = [Point(float(r["sim_time_s"]), float(r["wall_time_s"]),
                    PASS_COLOR if r["passed"] else FAIL_COLOR,
                    f"{_task_title(r)}; {r['sim_time_s']:g} s simulated, "
                    f"{r['wall_time_s']:g} s wall", base.of(r))
              for r in records if r["finish"] != "task_error"  # never ran
              and isinstance(r.get("sim_time_s"), int | float)
              and isinstance(r.get("wall_time_s"), int | float)]
    if not points:
        return ""
    sim = sum(p.x for p in points)
    wall = sum(p.y for p in points)
    speed = f"{sim / wall:,.0f}x" if wall > 0 else "n/a"
    note = (f"Each dot is a task (click to inspect it). {sim:,.0f} s simulated in "
            f"{wall:,.1f} s of the agent's wall time: {speed} faster than real time.")
    chart = scatter(points, label="Simulated against wall time per task",
                    x_label="simulated time of the task window",
                    y_label="agent wall time", legend=(("passed", PASS_COLOR),
                                                       ("failed", FAIL_COLOR)))
    return _panel("Simulated vs wall time", chart, escape(note), ident="times")


def _failed_table(records: Sequence[Record], base: TaskLinks) -> str:
    failed = [r for r in records if not r["passed"]]
    if not failed:
        return _panel("Failed tasks", '<p class="note">None: every task passed.</p>',
                      ident="failed")
    rows = []
    for r in failed:
        items = []
        for leaf in failed_leaves(r):
            threshold = (f' vs <span class="threshold">{escape(leaf.threshold)}</span>'
                         if leaf.threshold else "")
            note = f"<br>{escape(leaf.note)}" if leaf.note else ""
            items.append(f"<li><code>{escape(leaf.endpoint)}</code> {escape(leaf.subject)}: "
                         f'measured <span class="measured">{escape(leaf.measured)}</span>'
                         f'{threshold}<br><span class="leaf-condition">'
                         f"{escape(leaf.condition)}</span>{note}</li>")
        if r.get("error"):
            items.append(f"<li>{escape(str(r['finish']))}: {escape(str(r['error']))}</li>")
        if not items:
            items.append("<li>the check tree failed though every leaf passed</li>")
        rows.append(
            f'<tr><td><a href="{escape(base.of(r))}" target="_blank">'
            f"{escape(r['session'])} {escape(r['task'])}</a><br>"
            f'<span class="leaf-condition">{escape(str(r["template"]))}, '
            f"{escape(str(r['agent']))}, trial {int(r.get('trial', 0))}</span></td>"
            f"<td>{escape(str(r['finish']))}</td>"
            f'<td class="num">{r["checks_passed"]} / {r["checks_total"]}</td>'
            f'<td><ul class="leaves">{"".join(items)}</ul></td></tr>')
    table = ('<table><thead><tr><th>task</th><th>finish</th><th class="num">checks</th>'
             "<th>failing checks: measured vs threshold</th></tr></thead><tbody>"
             + "".join(rows) + "</tbody></table>")
    return _panel(f"Failed tasks ({len(failed)})", table, ident="failed")


def _all_table(records: Sequence[Record], base: TaskLinks) -> str:
    rows = []
    for r in records:
        tokens = r.get("tokens")
        total = (int(tokens.get("prompt", 0)) + int(tokens.get("completion", 0))
                 if isinstance(tokens, Mapping) else None)
        verdict = '<span class="pass">pass</span>' if r["passed"] else \
            '<span class="fail">fail</span>'
        rows.append(
            f'<tr><td><a href="{escape(base.of(r))}" target="_blank">'
            f"{escape(r['session'])} {escape(r['task'])}</a></td>"
            f"<td>{escape(str(r['template']))}</td><td>{escape(str(r['category']))}</td>"
            f"<td>{escape(str(r['agent']))}</td><td class=\"num\">{int(r.get('trial', 0))}</td>"
            f"<td>{verdict}</td>"
            f'<td class="num">{r["checks_passed"]} / {r["checks_total"]}</td>'
            f'<td class="num">{_num(r.get("tool_calls"), 0)}</td>'
            f'<td class="num">{_num(r.get("sim_time_s"))}</td>'
            f'<td class="num">{_num(r.get("wall_time_s"), 2)}</td>'
            f'<td class="num">{_num(total, 0) if total is not None else "-"}</td>'
            f"<td>{escape(str(r['finish']))}</td></tr>")
    head = ("<tr><th>task</th><th>template</th><th>category</th><th>agent</th>"
            '<th class="num">trial</th><th>verdict</th><th class="num">checks</th>'
            '<th class="num">calls</th><th class="num">sim s</th><th class="num">wall s</th>'
            '<th class="num">tokens</th><th>finish</th></tr>')
    return (f'<section class="panel" id="tasks"><details><summary>All tasks '
            f"({len(records)})</summary><table><thead>{head}</thead><tbody>"
            + "".join(rows) + "</tbody></table></details></section>")


def run_facts(records: Iterable[Record]) -> str:
    """What the records say a run ran with: its clock, model and link faults."""
    rows = list(records)

    def listed(name: str, missing: str) -> str:
        values = sorted({str(r[name]) for r in rows if r.get(name) not in (None, "", {})})
        return ", ".join(values) if values else missing

    return (f"clock: {listed('clock', 'not recorded')}; model: "
            f"{listed('model', 'not recorded')}; link faults: "
            f"{listed('link_faults', 'none recorded')}")


def _finish_note(summary: Mapping[str, Any]) -> str:
    finish = summary.get("finish") or {}
    parts = [f"{reason} {finish[reason]}" for reason in sorted(finish, key=finish_sort_key)]
    return "Finish reasons: " + ", ".join(parts) + "." if parts else ""


def render_html(records: Iterable[Record], *, title: str = "mavswarm benchmark",
                inspector_url: str = DEFAULT_INSPECTOR_URL, results_dir: str = "RESULTS_DIR",
                run_id: str | None = None) -> str:
    """The whole page for `records` (unique by key, the first wins). With `run_id` (the id
    ``mavswarm replay`` gives the results folder: its name) every task link names the run
    and the agent, so it opens this run's page when several runs are served."""
    base = check_inspector_url(inspector_url)
    links = TaskLinks(base, run_id)
    rows = unique(records)
    summary = summarize(rows)
    agents = ", ".join(summary.get("agents", [])) or "none"
    trials = summary.get("max_trials", 0)
    hint = (f"Every task links into the inspector at <code>{escape(base)}</code>, which shows "
            f"where the drones flew, each check and what the agent did. Start it first: "
            f"<code>mavswarm replay {escape(results_dir)}</code>.")
    parts = [
        f"<h1>{escape(title)}</h1>",
        f'<p class="sub">{len(rows)} tasks; agents: {escape(agents)}; '
        f"{escape(run_facts(rows))}; up to {trials} trial(s) per task. "
        f"{escape(_finish_note(summary))}</p>",
        f'<p class="hint">{hint}</p>',
    ]
    if not rows:
        parts.append(_panel("No results", '<p class="note">The results hold no record.</p>'))
    else:
        parts.append(_cards(summary["overall"], rows))
        agents_seen = summary.get("agents", [])
        if len(agents_seen) > 1:
            maps = "".join(f"<h3>{escape(a)}</h3>"
                           + _family_level_heatmap([r for r in rows if r["agent"] == a])
                           for a in agents_seen)
        else:
            maps = _family_level_heatmap(rows)
        parts.append(_panel("Pass rate by family and level", maps,
                            "Share of tasks whose check tree passed.", ident="heatmap"))
        by_category = hbars(_group_bars(summary["by_category"]), label="pass rate by category",
                            label_width=170, width=560)
        parts.append('<div class="grid">'
                     + _panel("Pass rate by category", by_category, ident="category")
                     + _panel("pass^k against k", _pass_hat_k(summary),
                              "Chance that k trials of a task all pass.", ident="passk")
                     + "</div>")
        by_agent = summary.get("by_agent")
        if isinstance(by_agent, Mapping):
            bars = [Bar(a, s["overall"]["task_pass_rate"], f"{s['overall']['passed_tasks']} / "
                        f"{s['overall']['tasks']}") for a, s in sorted(by_agent.items())]
            parts.append(_panel("Pass rate by agent",
                                hbars(bars, label="pass rate by agent", width=1000),
                                ident="agents"))
        endpoint_bars = _endpoint_bars(summary["by_endpoint"])
        parts.append(_panel("Check pass rate by endpoint",
                            hbars(endpoint_bars, label="check pass rate by endpoint",
                                  label_width=290, width=1000) if endpoint_bars else
                            '<p class="note">No check was evaluated.</p>',
                            "Leaf checks of each endpoint that passed, weakest first.",
                            ident="endpoints"))
        parts.append(_tokens(rows, links))
        parts.append(_times(rows, links))
        parts.append(_failed_table(rows, links))
        parts.append(_all_table(rows, links))
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            '<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<title>{escape(title)}</title><style>{PAGE_CSS}</style></head>"
            f"<body><main>{''.join(parts)}</main></body></html>\n")
