"""`bench compare` on records built directly: two agents that differ on known tasks give
exactly those paired transitions (overall and by family, level, category and template), the
rates and their intervals, endpoints side by side, pass^k, usage; runs on other tasks are
refused or compared on the intersection with a warning; compare.json has the generated
schema's shape; the command line writes the three files or says in one line what is wrong."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import jsonschema
import pytest

from benchmark.reporting.compare import CompareError, compare_paths, compare_schema, write_compare
from benchmark.reporting.compare.runs import task_fingerprint
from tests.cli_fixtures import MAVSWARM, run_in_process
from tests.compare_fixtures import record, write_results

# (session, task, family, level, category, template): outcome in A, outcome in B
KNOWN = {
    ("area_search-easy-1", "t01", "area_search", "easy", "navigation", "takeoff_hold"):
        (False, True),
    ("area_search-easy-1", "t02", "area_search", "easy", "photo", "photo_at_point"):
        (True, True),
    ("area_search-hard-1", "t01", "area_search", "hard", "navigation", "takeoff_hold"):
        (True, False),
    ("area_search-hard-1", "t02", "area_search", "hard", "photo", "photo_at_point"):
        (False, False),
    ("target_tracking-easy-1", "t01", "target_tracking", "easy", "navigation",
     "takeoff_hold"): (False, True),
    ("target_tracking-easy-1", "t02", "target_tracking", "easy", "photo", "photo_at_point"):
        (False, True),
}


def _runs(tmp_path: Path) -> tuple[Path, Path]:
    def records(agent: str, side: int) -> list[dict]:
        return [record(s, t, agent, outcome[side], family=f, level=lv, category=c, template=tp,
                       tokens={"prompt": 100, "completion": 10, "cost_usd": 0.002}
                       if agent == "better" else None)
                for (s, t, f, lv, c, tp), outcome in KNOWN.items()]
    return (write_results(tmp_path / "runA", records("base", 0)),
            write_results(tmp_path / "runB", records("better", 1)))


def test_two_agents_that_differ_on_known_tasks_give_exactly_those_transitions(
        tmp_path: Path) -> None:
    a, b = _runs(tmp_path)
    report = compare_paths([a, b])
    assert report.baseline == "runA" and [r.id for r in report.runs] == ["runA", "runB"]
    (pair,) = report.pairs
    t = pair.overall
    assert (t.fail_to_pass, t.pass_to_fail, t.both_pass, t.both_fail, t.pairs) == (3, 1, 1, 1, 6)
    assert t.mcnemar_p == pytest.approx(0.625)  # 2 * (1 + 4) / 16
    assert {(c.session, c.task, c.change) for c in pair.changed} == {
        ("area_search-easy-1", "t01", "fail_to_pass"),
        ("area_search-hard-1", "t01", "pass_to_fail"),
        ("target_tracking-easy-1", "t01", "fail_to_pass"),
        ("target_tracking-easy-1", "t02", "fail_to_pass")}
    fam = {k: (v.fail_to_pass, v.pass_to_fail, v.both_pass, v.both_fail)
           for k, v in pair.by_family.items()}
    assert fam == {"area_search": (1, 1, 1, 1), "target_tracking": (2, 0, 0, 0)}
    assert list(pair.by_level) == ["easy", "hard"]  # difficulty order
    assert (pair.by_level["hard"].pass_to_fail, pair.by_level["easy"].fail_to_pass) == (1, 3)
    assert (pair.by_category["photo"].fail_to_pass, pair.by_category["photo"].both_pass,
            pair.by_category["photo"].both_fail) == (1, 1, 1)
    assert pair.by_template["takeoff_hold"].pairs == 3
    # Rates: A passes 2/6, B 4/6; the paired difference is +2/6.
    runs = {r.id: r for r in report.runs}
    assert runs["runA"].task_pass_rate.value == pytest.approx(2 / 6, abs=1e-6)
    assert runs["runB"].task_pass_rate.value == pytest.approx(4 / 6, abs=1e-6)
    assert pair.task_pass_rate_diff.value == pytest.approx(2 / 6, abs=1e-6)
    for run in report.runs:
        assert run.task_pass_rate.low <= run.task_pass_rate.value <= run.task_pass_rate.high
    assert runs["runB"].by_endpoint["drone_has_taken_off"].passed == 4
    assert runs["runB"].tokens.prompt == 600 and runs["runB"].tokens.cost_usd == 0.012
    assert runs["runA"].tokens.records == 0 and runs["runA"].time.sim_time_s == 240.0
    assert runs["runA"].clocks == ["lockstep"] and runs["runA"].models == []
    assert report.sessions == 3 and report.tasks == 6
    assert any("only 3 session(s)" in w for w in report.warnings)
    # The same inputs give the same report, byte for byte.
    assert compare_paths([a, b]).model_dump_json() == report.model_dump_json()


def test_baseline_pass_hat_k_and_a_file_with_two_agents(tmp_path: Path) -> None:
    a, b = _runs(tmp_path)
    report = compare_paths([a, b], baseline="runB")
    assert report.baseline == "runB" and report.pairs[0].run == "runA"
    assert report.pairs[0].overall.pass_to_fail == 3  # seen from B
    # One file holding two agents, three trials each: one run per agent.
    rows = [record("s1", f"t{k}", agent, passed=(agent == "x" or trial < k), trial=trial)
            for agent in ("x", "y") for k in range(3) for trial in range(3)]
    both = write_results(tmp_path / "both", rows)
    report = compare_paths([both])
    assert [r.id for r in report.runs] == ["both:x", "both:y"]
    assert report.runs[1].console_run == "both" and report.runs[1].agent == "y"
    y = report.runs[1]
    # y passes t1 once and t2 twice of three trials: pass^1 = (0 + 1/3 + 2/3) / 3.
    assert y.max_trials == 3 and y.pass_hat_k["1"] == pytest.approx(1 / 3, abs=1e-6)
    assert y.pass_hat_k["3"] == 0.0 and report.runs[0].pass_hat_k["3"] == 1.0
    assert report.pairs[0].overall.pairs == 9  # paired by (session, task, trial)


def test_runs_on_other_tasks_are_refused_or_intersected(tmp_path: Path) -> None:
    a, _ = _runs(tmp_path)
    fewer = write_results(tmp_path / "fewer", [record("area_search-easy-1", "t01", "z", True),
                                               record("area_search-easy-1", "t09", "z", True)])
    with pytest.raises(CompareError, match="not made on the same tasks") as caught:
        compare_paths([a, fewer])
    assert "--intersect" in str(caught.value) and "area_search-easy-1/t09" in str(caught.value)
    report = compare_paths([a, fewer], intersect=True)
    assert report.tasks == 1 and report.pairs[0].overall.fail_to_pass == 1
    assert any(w.startswith("compared on the intersection") for w in report.warnings)
    assert any("runA: 5 task(s) outside the intersection" in w for w in report.warnings)
    # A suite_fingerprint field wins over the task-set hash; runs on other suites differ.
    other = write_results(tmp_path / "other", [
        {**r, "agent": "w", "key": r["key"].replace("/base/", "/w/"),
         "suite_fingerprint": "suite-v2"}
        for r in (json.loads(line) for line in
                  (a / "results.jsonl").read_text().splitlines())])
    with pytest.raises(CompareError, match="was run on suite suite-v2"):
        compare_paths([a, other])
    assert compare_paths([a, other], intersect=True).fingerprints == sorted(
        ["suite-v2", task_fingerprint((s, t) for s, t, *_ in KNOWN)])
    with pytest.raises(CompareError, match="at least two runs"):
        compare_paths([a])
    with pytest.raises(CompareError, match="given twice"):
        compare_paths([a, a / "results.jsonl"])
    with pytest.raises(CompareError, match="--baseline 'nope' is none of the runs"):
        compare_paths([a, fewer], baseline="nope", intersect=True)


def test_compare_json_has_the_generated_schemas_shape(tmp_path: Path) -> None:
    a, b = _runs(tmp_path)
    md, js, html = write_compare(compare_paths([a, b]), tmp_path / "out")
    document = json.loads(js.read_text())
    jsonschema.validate(document, compare_schema())
    assert set(document["pairs"][0]["overall"]) >= {"fail_to_pass", "pass_to_fail",
                                                     "both_pass", "both_fail", "mcnemar_p"}
    text = md.read_text()
    assert "| runB | 6 | 3 | 1 | 1 | 1 | +33.3 pp | 0.625 |" in text
    assert "## By category" in text and "## Check pass rate by endpoint" in text
    assert html.read_text().startswith("<!DOCTYPE html>")


@pytest.mark.slow
def test_compare_command_line(tmp_path: Path) -> None:
    a, b = _runs(tmp_path)
    out = tmp_path / "cmp"
    done = subprocess.run([*MAVSWARM, "bench", "compare", str(a), str(b), "--out", str(out),
                           "--resamples", "500"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "runB vs runA: 3 fail->pass, 1 pass->fail, 1 both pass, 1 both fail" in done.stdout
    assert "McNemar p = 0.625" in done.stdout and "only 3 session(s)" in done.stderr
    assert sorted(p.name for p in out.iterdir()) == ["compare.html", "compare.json",
                                                     "compare.md"]
    assert json.loads((out / "compare.json").read_text())["bootstrap"]["resamples"] == 500
    bad_out = tmp_path / "bad"
    for args, message in (
            ([str(a), str(tmp_path / "missing")], "no such results folder or file"),
            ([str(a), str(b), "--baseline", "runC"], "--baseline 'runC' is none of the runs"),
            ([str(a), str(b), "--resamples", "5"], "resamples must be an integer >= 100"),
            ([str(a), str(b), "--inspector-url", "ftp://x"], "--inspector-url must be")):
        bad = run_in_process("bench", "compare", *args, "--out", str(bad_out), cwd=tmp_path)
        assert bad.returncode == 2 and message in bad.stderr, (args, bad.stderr)
        assert len(bad.stderr.strip().splitlines()) == 1 and "Traceback" not in bad.stderr
    assert not bad_out.exists()
