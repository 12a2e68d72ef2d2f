"""`bench report` of several runs reports each on its own (agents, clock, model, link faults,
its own metrics), never one pooled headline, and every task link names its run."""

from __future__ import annotations

import json
import re
from pathlib import Path

from benchmark.reporting.report import write_report
from benchmark.reporting.report_html import inspector_link
from tests.cli_fixtures import run_in_process
from tests.compare_fixtures import record, write_results


def _two_runs(tmp_path: Path) -> tuple[Path, Path]:
    a = write_results(tmp_path / "oracle", [record("s1", f"t{k}", "oracle", True)
                                            for k in range(4)])
    b = write_results(tmp_path / "sub" / "oracle", [
        record("s1", f"t{k}", "react", k == 0, model="tiny-model",
               link_faults={"loss": 0.1}) for k in range(4)])
    return a, b


def test_several_runs_are_reported_apart(tmp_path: Path) -> None:
    a, b = _two_runs(tmp_path)  # both folders are named "oracle": ids oracle and oracle+
    out = tmp_path / "rep"
    done = run_in_process("bench", "report", str(a), str(b / "results.jsonl"),
                          "--out", str(out), "--inspector-url", "http://h.test:9", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "| Task Pass Rate | 100.0 % | 4 / 4 tasks |" in done.stdout
    assert "| Task Pass Rate | 25.0 % | 1 / 4 tasks |" in done.stdout
    assert "62.5 %" not in done.stdout  # the pooled rate of both runs
    document = json.loads((out / "report.json").read_text())
    assert "overall" not in document
    first, second = document["runs"]
    assert (first["id"], second["id"]) == ("oracle", "oracle+")
    assert first["summary"]["overall"]["task_pass_rate"] == 1.0
    assert second["summary"]["overall"]["task_pass_rate"] == 0.25
    assert (second["agents"], second["models"], second["clocks"]) == (
        ["react"], ["tiny-model"], ["lockstep"])
    assert second["link_faults"] == ["{'loss': 0.1}"] and first["link_faults"] == []
    markdown = (out / "report.md").read_text()
    assert "## Run oracle\n" in markdown and "## Run oracle+\n" in markdown
    assert "model: tiny-model" in markdown
    assert {p.name for p in out.glob("report-*.html")} == {"report-oracle.html",
                                                          "report-oracle+.html"}
    for name, run, agent in (("report-oracle.html", "oracle", "oracle"),
                             ("report-oracle+.html", "oracle%2B", "react")):
        links = re.findall(r'href="(http://h\.test:9/inspect/[^"]+)"',
                           (out / name).read_text())
        assert len(links) >= 4 and all(f"run={run}&amp;agent={agent}&amp;trial=0" in link
                                       for link in links), links
    index = (out / "report.html").read_text()
    assert "never pooled" in index and index.count("<tr><td><a href=") == 2


def test_a_single_runs_links_name_it_when_its_id_is_known(tmp_path: Path) -> None:
    a, _ = _two_runs(tmp_path)
    records = [json.loads(line) for line in (a / "results.jsonl").read_text().splitlines()]
    _, _, html = write_report(records, tmp_path / "one", run_id="oracle")
    page = html.read_text()
    link = inspector_link("http://127.0.0.1:8765", "s1", "t0", 0, run="oracle", agent="oracle")
    assert link == "http://127.0.0.1:8765/inspect/s1/t0?run=oracle&agent=oracle&trial=0"
    assert link.replace("&", "&amp;") in page
