"""``bench report`` of several runs: each run reported on its own, never pooled.

``report.md`` and ``report.json`` hold one section per run (what it ran with: agents, clock,
model, link faults; then its own summary); ``report.html`` is an index of the runs linking
one full page per run (``report-<run id>.html``), whose task links name that run, so each
opens that run's inspector page when ``mavswarm replay`` serves all of them.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from html import escape
from pathlib import Path
from typing import Any

from benchmark.reporting.report import render_markdown, write_text_atomic
from benchmark.reporting.report_html import (
    DEFAULT_INSPECTOR_URL,
    PAGE_CSS,
    check_inspector_url,
    render_html,
    run_facts,
)
from benchmark.running.results import ResultsError, read_task_records
from benchmark.scoring.metrics import summarize

__all__ = ["ReportRun", "load_report_runs", "write_runs_report"]


@dataclass
class ReportRun:
    """One results file and the id `mavswarm replay` gives its folder."""

    id: str
    source: Path
    records: list[dict[str, Any]] = field(default_factory=list)

    @property
    def page_name(self) -> str:
        return "report-" + re.sub(r"[^A-Za-z0-9_.+-]+", "-", self.id).strip("-.") + ".html"


def load_report_runs(paths: Sequence[Path]) -> list[ReportRun]:
    """A run per results file (or folder holding one), ids as the replay server gives them:
    the folder's name, with ``+`` added while taken. A file given twice is refused."""
    runs: list[ReportRun] = []
    seen: set[Path] = set()
    for path in paths:
        file = path / "results.jsonl" if path.is_dir() else path
        if file.resolve() in seen:
            raise ResultsError(f"{path}: this results file is given twice")
        seen.add(file.resolve())
        run_id = file.resolve().parent.name or "run"
        while any(r.id == run_id for r in runs):
            run_id += "+"
        records = read_task_records(file)
        if not records:
            raise ResultsError(f"{path}: no task records to report")
        runs.append(ReportRun(run_id, file, records))
    return runs


def _meta(run: ReportRun, summary: Mapping[str, Any]) -> dict[str, Any]:
    def listed(name: str) -> list[str]:
        return sorted({str(r[name]) for r in run.records if r.get(name) not in (None, "", {})})
    return {"id": run.id, "source": str(run.source), "agents": summary.get("agents", []),
            "clocks": listed("clock"), "models": listed("model"),
            "link_faults": listed("link_faults")}


def _demoted(markdown: str) -> str:
    return "\n".join("#" + line if line.startswith("#") else line
                     for line in markdown.splitlines())


def _pct(rate: float) -> str:
    return f"{rate * 100:.1f} %"


def _index(runs: Sequence[tuple[ReportRun, Mapping[str, Any]]], title: str) -> str:
    rows = []
    for run, summary in runs:
        o = summary["overall"]
        rows.append(
            f'<tr><td><a href="{escape(run.page_name)}">{escape(run.id)}</a></td>'
            f"<td>{escape(', '.join(summary.get('agents', [])))}</td>"
            f"<td>{escape(run_facts(run.records))}</td>"
            f'<td class="num">{o["tasks"]}</td>'
            f'<td class="num">{_pct(o["task_pass_rate"])} ({o["passed_tasks"]}/{o["tasks"]})</td>'
            f'<td class="num">{_pct(o["average_check_pass_rate"])}</td>'
            f'<td class="num">{_pct(o["check_pass_rate"])}</td>'
            f'<td class="num">{_pct(o["total_failed_task_rate"])}</td></tr>')
    table = ('<table id="runs-table"><thead><tr><th>run</th><th>agents</th><th>ran with</th>'
             '<th class="num">tasks</th><th class="num">Task Pass</th>'
             '<th class="num">Avg. Check</th><th class="num">Global Check</th>'
             '<th class="num">Total Failed</th></tr></thead><tbody>' + "".join(rows)
             + "</tbody></table>")
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{escape(title)}</title><style>{PAGE_CSS}</style></head><body><main>"
            f"<h1>{escape(title)}</h1><p class=\"sub\">{len(runs)} runs, each reported on its "
            "own page (never pooled). To compare them task by task, with intervals: "
            "<code>mavswarm bench compare</code>.</p>"
            f'<section class="panel" id="runs">{table}</section></main></body></html>\n')


def write_runs_report(runs: Sequence[ReportRun], out_dir: str | Path, *,
                      title: str = "mavswarm benchmark",
                      inspector_url: str = DEFAULT_INSPECTOR_URL) -> tuple[Path, ...]:
    """Write report.md, report.json, report.html (the index) and one page per run into
    `out_dir`; returns their paths, the index third."""
    check_inspector_url(inspector_url)
    directory = Path(out_dir)
    summaries = [(run, summarize(run.records)) for run in runs]
    pages = {run.page_name: render_html(run.records, title=f"{title}: {run.id}",
                                        inspector_url=inspector_url,
                                        results_dir=str(run.source.parent), run_id=run.id)
             for run in runs}
    if len(pages) != len(runs):
        raise ValueError("two runs' ids give the same page name: "
                         + ", ".join(run.id for run in runs))
    md = [f"# {title}", "", f"{len(runs)} runs, each reported on its own."]
    for run, summary in summaries:
        meta = _meta(run, summary)
        md += ["", _demoted(render_markdown(summary, title=f"Run {run.id}")).rstrip(), "",
               f"source {meta['source']}; agents {', '.join(meta['agents']) or 'none'}; "
               f"{run_facts(run.records)}"]
    document = {"runs": [{**_meta(run, summary), "summary": summary}
                         for run, summary in summaries]}
    directory.mkdir(parents=True, exist_ok=True)
    paths = [directory / "report.md", directory / "report.json", directory / "report.html"]
    write_text_atomic(paths[0], "\n".join(md) + "\n")
    write_text_atomic(paths[1], json.dumps(document, sort_keys=True, indent=2) + "\n")
    write_text_atomic(paths[2], _index(summaries, title))
    for name, page in pages.items():
        write_text_atomic(directory / name, page)
        paths.append(directory / name)
    return tuple(paths)
