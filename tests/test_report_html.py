"""report.html from a real benchmark run (the oracle and the do-nothing agent over MAVLink):
the numbers and failing checks the records hold, a link into the inspector for every task,
nothing loaded from anywhere else, and the charts rendered by headless Chromium."""

from __future__ import annotations

import html
import json
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import pytest

from benchmark.reporting.report import write_report
from benchmark.reporting.report_html import (
    DEFAULT_INSPECTOR_URL,
    check_inspector_url,
    inspector_link,
    render_html,
)
from benchmark.running.orchestrator import RunPlan, run_benchmark
from benchmark.running.results import read_records
from benchmark.scoring.failed_checks import failed_leaves
from benchmark.scoring.metrics import summarize
from tests.bench_fixtures import small_session, write_json
from tests.scripted_llm import call, scripted_llm

KEYS = ["takeoff_hold", "climb_and_face"]
CHROMIUM = shutil.which("chromium")
CHART_IDS = ("heatmap", "category", "passk", "agents", "endpoints", "tokens", "times")


@pytest.fixture(scope="module")
def results(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One results file with the records of two tasks flown by the oracle (both pass), the
    noop agent (both fail) and the ReAct agent on a scripted model with prices (the first
    passes, the second fails; 200 + 40 and 100 + 20 tokens)."""
    folder = tmp_path_factory.mktemp("run")
    data = small_session(KEYS)
    op = data["tasks"][0]["oracle"][0][0]
    session = write_json(folder / "s.json", data)
    for agent in ("oracle", "noop"):
        run_benchmark(RunPlan(sessions=(session,), agent=agent, out_dir=folder / "out"),
                      progress=lambda _: None)
    script = [[call("take_off", {"drone_id": op["drone"], "altitude_m": op["altitude_m"]})],
              [call("finish", {})]]
    with scripted_llm(script) as llm:
        run_benchmark(RunPlan(sessions=(session,), agent="react", out_dir=folder / "out",
                              model="scripted", base_url=llm.base_url,
                              price_in_usd_per_mtok=2.0, price_out_usd_per_mtok=8.0),
                      progress=lambda _: None)
    return folder / "out" / "results.jsonl"


class _Refs(HTMLParser):
    """Every src/href attribute and every tag name of a page."""

    def __init__(self) -> None:
        super().__init__()
        self.refs: list[tuple[str, str, str]] = []
        self.tags: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append(tag)
        for name, value in attrs:
            if name in ("src", "href", "xlink:href", "srcset", "action", "data"):
                self.refs.append((tag, name, value or ""))


def _parse(page: str) -> _Refs:
    parser = _Refs()
    parser.feed(page)
    return parser


@pytest.mark.mavsdk
@pytest.mark.slow
def test_report_html_holds_the_run(results: Path, tmp_path: Path) -> None:
    records = read_records(results)
    assert len(records) == 6
    assert {(r["agent"], r["task"]): r["passed"] for r in records} == {
        ("oracle", "t01"): True, ("oracle", "t02"): True, ("noop", "t01"): False,
        ("noop", "t02"): False, ("react", "t01"): True, ("react", "t02"): False}
    _, _, html_path = write_report(records, tmp_path, results_dir=results.parent)
    page = html_path.read_text(encoding="utf-8")
    overall = summarize(records)["overall"]
    assert "50.0 %" in page and "3 / 6 tasks" in page  # Task Pass Rate
    assert "2 tasks report tokens: median 180, max 240 tokens per task" in page
    assert "cost 0.0011 USD in all" in page  # 0.00072 + 0.00036
    assert f"{overall['passed_checks']} / {overall['total_checks']} checks" in page
    assert f"mavswarm replay {results.parent}" in page
    # Every task links to its inspector page; only failed ones appear in the failed table.
    for r in records:
        assert inspector_link(DEFAULT_INSPECTOR_URL, r["session"], r["task"], r["trial"]) in page
    failed = page[page.index('id="failed"'):page.index('id="tasks"')]
    assert "Failed tasks (3)" in failed
    for r in records:
        for check in r["checks"]:
            if not check["passed"]:
                assert f"<code>{check['endpoint']}</code>" in failed
                params = check["parameters"]
                if params.get("tolerance") is not None:
                    assert f"tolerance {params['tolerance']:g}" in failed
    # Charts are inline SVG, one per chart panel.
    for ident in CHART_IDS:
        section = page[page.index(f'id="{ident}"'):]
        assert section.index("<svg") < section.index("</section>"), ident
    # Self-contained: no scripts, stylesheets, images or frames from elsewhere; the only
    # absolute URLs are the inspector's task pages.
    parsed = _parse(page)
    assert not {"script", "link", "img", "iframe", "object", "embed"} & set(parsed.tags)
    assert "@import" not in page and "url(" not in page
    external = [ref for ref in parsed.refs if re.match(r"(?i)\s*(https?:)?//", ref[2])]
    assert external and all(
        tag == "a" and name == "href" and value.startswith(f"{DEFAULT_INSPECTOR_URL}/inspect/")
        for tag, name, value in external), external
    assert not [ref for ref in parsed.refs if not re.match(r"(?i)https?://", ref[2])]


@pytest.mark.mavsdk
@pytest.mark.slow
def test_report_command_takes_the_inspector_url(results: Path, tmp_path: Path) -> None:
    from tests.cli_fixtures import run_in_process
    out = tmp_path / "rep"
    done = run_in_process("bench", "report", str(results), "--out", str(out),
                          "--inspector-url", "http://inspector.test:9000/", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert str(out / "report.html") in done.stdout
    page = (out / "report.html").read_text(encoding="utf-8")
    links = re.findall(r'href="([^"]+)"', page)
    assert links and all(link.startswith("http://inspector.test:9000/inspect/")
                         for link in links)
    assert "http://127.0.0.1:8765" not in page
    bad = run_in_process("bench", "report", str(results), "--out", str(tmp_path / "bad"),
                         "--inspector-url", "ftp://x", cwd=tmp_path)
    assert bad.returncode == 2 and "--inspector-url" in bad.stderr and "ftp://x" in bad.stderr
    assert not (tmp_path / "bad").exists()


def test_report_of_no_records_says_so(tmp_path: Path) -> None:
    _, _, html_path = write_report([], tmp_path)
    assert "The results hold no record." in html_path.read_text(encoding="utf-8")


_HARNESS = """<!DOCTYPE html><html><body><pre id="out">pending</pre>
<iframe id="page" src="report.html" style="width:1300px;height:900px"></iframe>
<script>
document.getElementById("page").addEventListener("load", () => {
  const doc = document.getElementById("page").contentDocument;
  const charts = {};
  for (const panel of doc.querySelectorAll("section.panel[id]")) {
    const svgs = [...panel.querySelectorAll("svg.chart")];
    charts[panel.id] = svgs.map(svg => {
      const box = svg.getBoundingClientRect();
      const marks = [...svg.querySelectorAll("rect, circle")].filter(m => {
        const b = m.getBoundingClientRect();
        return b.width > 0 && b.height > 0 && getComputedStyle(m).fill !== "none";
      });
      return {width: box.width, height: box.height, marks: marks.length};
    });
  }
  const cell = doc.querySelector("#heatmap svg rect");
  document.getElementById("out").textContent = JSON.stringify(
    {charts, cellFill: cell ? getComputedStyle(cell).fill : null,
     links: doc.querySelectorAll("a[href*='/inspect/']").length});
});
</script></body></html>"""


@pytest.mark.mavsdk
@pytest.mark.slow
@pytest.mark.skipif(CHROMIUM is None, reason="headless Chromium is not installed "
                    "(.ci/run installs Debian's chromium)")
def test_chromium_renders_the_charts(results: Path, tmp_path: Path) -> None:
    records = read_records(results)
    _, _, html_path = write_report(records, tmp_path)
    (tmp_path / "harness.html").write_text(_HARNESS, encoding="utf-8")
    dom = subprocess.run(
        [str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu",
         "--allow-file-access-from-files", "--virtual-time-budget=5000",
         "--dump-dom", (tmp_path / "harness.html").as_uri()],
        capture_output=True, text=True, timeout=120)
    found = re.search(r'<pre id="out">(.*?)</pre>', dom.stdout, re.S)
    assert found and found.group(1) != "pending", dom.stdout[-2000:] + dom.stderr[-2000:]
    measured = json.loads(html.unescape(found.group(1)))
    for ident in CHART_IDS:
        charts = measured["charts"][ident]
        assert charts, ident
        for chart in charts:
            assert chart["width"] > 150 and chart["height"] > 40 and chart["marks"] > 0, \
                (ident, chart)
    # One heatmap per agent; cells are drawn in the scale's colours.
    assert len(measured["charts"]["heatmap"]) == 3
    assert measured["cellFill"] not in (None, "none", "rgb(0, 0, 0)")
    assert measured["links"] >= 2 * len(records)
    shot = tmp_path / "shot.png"
    subprocess.run([str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu",
                    "--hide-scrollbars", f"--screenshot={shot}", "--window-size=1300,2400",
                    html_path.as_uri()], capture_output=True, timeout=120, check=True)
    data = shot.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 60_000  # a blank page is ~10 kB


def test_inspector_links_and_url_checks() -> None:
    assert inspector_link("http://h:1/", "a b/c", "t 1", 2) == \
        "http://h:1/inspect/a%20b%2Fc/t%201?trial=2"
    assert check_inspector_url(" https://x.test/base/ ") == "https://x.test/base"
    for bad in ("ftp://x", "127.0.0.1:8765", "", "http://"):
        with pytest.raises(ValueError, match="--inspector-url must be an http"):
            check_inspector_url(bad)


def test_failed_leaves_split_subject_measure_and_threshold() -> None:
    record = {"checks": [
        {"path": "checks[0]", "endpoint": "drone_has_visited_position", "passed": False,
         "parameters": {"drone_id": "d1", "x": 121.0, "y": 186.0, "z": 19.0,
                        "tolerance": 3.0}, "expect": True, "result": False,
         "value": 391.70612, "error": None},
        {"path": "checks[1]", "endpoint": "drone_on_ground", "passed": False,
         "parameters": {"drone_id": "d2", "tolerance": 1.5}, "expect": False,
         "result": True, "value": 0.0, "error": None},
        {"path": "checks[2]", "endpoint": "two_drones_distance", "passed": False,
         "parameters": {"drone_1_id": "d1", "drone_2_id": "d3", "max_distance": 45.0,
                        "min_distance": None}, "expect": True, "result": None,
         "value": None, "error": "drone d3 has no track"},
        {"path": "checks[3]", "endpoint": "drone_altitude", "passed": True,
         "parameters": {}, "expect": True, "result": True, "value": 1, "error": None},
    ]}
    visited, ground, distance = failed_leaves(record)
    assert (visited.subject, visited.measured, visited.threshold) == (
        "d1, at (121, 186, 19)", "391.706", "tolerance 3")
    assert visited.condition.startswith("the flown trajectory passed within tolerance")
    assert ground.note == "the task wanted this check false; it was true"
    assert (distance.subject, distance.measured, distance.threshold) == (
        "d1, d3", "none", "max_distance 45")
    assert distance.note == "error: drone d3 has no track"


def test_names_from_the_records_are_escaped(tmp_path: Path) -> None:
    record = {"key": "k", "session": "<script>alert(1)</script>", "family": "f<b>",
              "level": "easy", "task": 't"1', "template": "x", "category": "c",
              "agent": "a", "trial": 0, "passed": False, "checks": [], "checks_total": 0,
              "checks_passed": 0, "finish": "task_error", "error": "<img src=x>",
              "tool_calls": 0, "sim_time_s": 0.0, "wall_time_s": 0.0, "tokens": None}
    page = render_html([record])
    tags = set(_parse(page).tags)
    assert "script" not in tags and "img" not in tags and "b" not in tags
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in page and "&lt;img src=x&gt;" in page
