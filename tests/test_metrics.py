"""Tests for benchmark metrics, breakdowns, pass^k and the Markdown/JSON report."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from benchmark.reporting.report import metrics_table, render_markdown, write_report
from benchmark.scoring.metrics import (
    Metrics,
    breakdown,
    compute_metrics,
    endpoint_breakdown,
    pass_hat_k,
    summarize,
)


def _rec(
    key: str,
    *,
    passed: bool = True,
    total: int = 2,
    passing: int | None = None,
    family: str = "area_search",
    level: str = "easy",
    category: str = "navigation",
    template: str = "quick_checkpoint",
    agent: str = "oracle",
    session: str | None = None,
    task: str | None = None,
    trial: int = 0,
    finish: str = "finished",
    checks: list[dict[str, Any]] | None = None,
    **extra: Any,
) -> dict[str, Any]:
    passing = total if passing is None else passing
    return {
        "key": key,
        "session": session or f"{family}-{level}-1",
        "family": family,
        "level": level,
        "task": task or key,
        "template": template,
        "category": category,
        "agent": agent,
        "trial": trial,
        "passed": passed,
        "checks": checks or [],
        "checks_total": total,
        "checks_passed": passing,
        "finish": finish,
        "error": None,
        "tool_calls": 5,
        "sim_time_s": 100.0,
        "wall_time_s": 2.0,
        "tokens": None,
        **extra,
    }


def _check(endpoint: str, passed: bool) -> dict[str, Any]:
    return {"path": "checks[0]", "endpoint": endpoint, "parameters": {}, "passed": passed}


def _sanity_records() -> list[dict[str, Any]]:
    """1500 tasks: 1054 pass all 6 checks, 93 pass none, 353 pass 3 of 6."""
    records = []
    for i in range(1500):
        if i < 1054:
            records.append(_rec(f"t{i}", total=6, passing=6))
        elif i < 1054 + 93:
            records.append(_rec(f"t{i}", passed=False, total=6, passing=0))
        else:
            records.append(_rec(f"t{i}", passed=False, total=6, passing=3))
    return records


def test_spec_sanity_numbers() -> None:
    metrics = compute_metrics(_sanity_records())
    assert metrics.tasks == 1500
    assert metrics.passed_tasks == 1054
    assert metrics.total_failed_task_count == 93
    as_json = metrics.to_json()
    assert as_json["task_pass_rate"] == 0.7027
    assert as_json["total_failed_task_rate"] == 0.062
    assert metrics.total_checks == 9000
    assert metrics.passed_checks == 1054 * 6 + 353 * 3
    assert as_json["check_pass_rate"] == round((1054 * 6 + 353 * 3) / 9000, 4)


def test_formulas_with_zero_check_task() -> None:
    records = [
        _rec("a", passed=False, total=4, passing=2, tool_calls=3, sim_time_s=10.0),
        _rec("b", passed=True, total=0, passing=0, tool_calls=None, sim_time_s=None),
        _rec("c", passed=True, total=3, passing=3, tool_calls=6, sim_time_s=30.0),
    ]
    metrics = compute_metrics(records)
    assert metrics.task_pass_rate == pytest.approx(2 / 3)
    # The zero-check task adds 0 to the sum but still counts in N.
    assert metrics.average_check_pass_rate == pytest.approx((0.5 + 0.0 + 1.0) / 3)
    assert metrics.check_pass_rate == pytest.approx(5 / 7)
    # A zero-check task has p_i = 0, so it counts as totally failed.
    assert metrics.total_failed_task_count == 1
    assert metrics.total_failed_task_rate == pytest.approx(1 / 3)
    assert metrics.mean_tool_calls == pytest.approx(4.5)
    assert metrics.mean_sim_time_s == pytest.approx(20.0)
    assert metrics.mean_wall_time_s == pytest.approx(2.0)
    assert metrics.to_json()["average_check_pass_rate"] == 0.5


def test_empty_records_give_zero_rates_and_no_means() -> None:
    metrics = compute_metrics([])
    assert metrics == Metrics(0, 0, 0.0, 0.0, 0, 0, 0.0, 0, 0.0, None, None, None)
    summary = summarize([])
    assert summary["pass_hat_k"] == {}
    assert summary["agents"] == []
    assert "70" not in metrics_table(summary)


def test_repeated_key_keeps_first_record() -> None:
    records = [_rec("a", passed=True), _rec("a", passed=False, passing=0), _rec("b")]
    metrics = compute_metrics(records)
    assert metrics.tasks == 2
    assert metrics.passed_tasks == 2


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"passed": 1}, r"record 'x': field 'passed' must be a boolean, got 1"),
        ({"checks_total": -1}, r"field 'checks_total' must be a non-negative integer, got -1"),
        ({"checks_passed": 3}, r"'checks_passed' \(3\) exceeds 'checks_total' \(2\)"),
        ({"tool_calls": "many"}, r"field 'tool_calls' must be a finite number or null"),
    ],
)
def test_bad_records_are_reported(change: dict[str, Any], message: str) -> None:
    record = _rec("x") | change
    with pytest.raises(ValueError, match=message):
        compute_metrics([record])


def test_breakdown_orders_levels_by_difficulty_and_names_alphabetically() -> None:
    levels = ["hard", "easy", "extreme", "intermediate", "moderate", "easy"]
    families = ["target_assignment", "area_search", "area_assignment_and_patrol"] * 2
    records = [
        _rec(f"k{i}", level=level, family=family, passed=i < 3)
        for i, (level, family) in enumerate(zip(levels, families, strict=True))
    ]
    by_level = breakdown(records, "level")
    assert list(by_level) == ["easy", "intermediate", "moderate", "hard", "extreme"]
    assert by_level["easy"].tasks == 2
    assert by_level["easy"].passed_tasks == 1
    by_family = breakdown(records, "family")
    assert list(by_family) == ["area_assignment_and_patrol", "area_search", "target_assignment"]
    with pytest.raises(ValueError, match=r"'by' must be one of .* got 'colour'"):
        breakdown(records, "colour")
    with pytest.raises(ValueError, match="field 'template' must be a non-empty string"):
        breakdown([_rec("z", template="")], "template")


def test_endpoint_breakdown_counts_leaf_checks() -> None:
    records = [
        _rec("a", checks=[_check("drone_altitude", True), _check("drone_on_ground", False)]),
        _rec("b", checks=[_check("drone_altitude", False), _check("drone_altitude", True)]),
    ]
    result = endpoint_breakdown(records)
    assert list(result) == ["drone_altitude", "drone_on_ground"]
    assert result["drone_altitude"] == {"checks": 3, "passed": 2, "pass_rate": 0.6667}
    assert result["drone_on_ground"] == {"checks": 1, "passed": 0, "pass_rate": 0.0}


def _trials(task: str, outcomes: list[bool], agent: str = "oracle") -> list[dict[str, Any]]:
    return [
        _rec(f"s/{task}/{agent}/{n}", session="s", task=task, agent=agent, trial=n, passed=ok)
        for n, ok in enumerate(outcomes)
    ]


def test_pass_hat_k_known_values() -> None:
    records = _trials("t1", [True, False, True, False])
    assert pass_hat_k(records, 1) == pytest.approx(0.5)
    assert pass_hat_k(records, 2) == pytest.approx(1 / 6)
    assert pass_hat_k(records, 4) == 0.0
    assert pass_hat_k(records, 5) is None


def test_pass_hat_k_means_over_tasks_with_enough_trials() -> None:
    records = (
        _trials("t1", [True, True, True])
        + _trials("t2", [True, False, True])
        + _trials("t3", [True])
        + _trials("t1", [False, False, False], agent="other")
    )
    # k=2: t1/oracle 1, t2/oracle C(2,2)/C(3,2) = 1/3, t1/other 0; t3 has too few trials.
    assert pass_hat_k(records, 2) == pytest.approx((1 + 1 / 3 + 0) / 3)
    assert pass_hat_k(records, 1) == pytest.approx((1 + 2 / 3 + 1 + 0) / 4)
    with pytest.raises(ValueError, match="'k' must be a positive integer, got 0"):
        pass_hat_k(records, 0)


def test_summarize_shape_and_per_agent_section() -> None:
    records = (
        _trials("t1", [True, False])
        + _trials("t1", [False, False], agent="llm")
        + [_rec("x", finish="tool_call_budget", passed=False, passing=0, agent="llm")]
        + [
            _rec(
                "y",
                finish="agent_error",
                passed=False,
                passing=0,
                tokens={"prompt": 10, "completion": 4},
            )
        ]
    )
    summary = summarize(records)
    json.dumps(summary)
    assert summary["overall"]["tasks"] == 6
    assert summary["max_trials"] == 2
    assert list(summary["pass_hat_k"]) == ["1", "2"]
    assert summary["pass_hat_k"]["2"] == 0.0
    assert list(summary["finish"]) == ["finished", "tool_call_budget", "agent_error"]
    assert summary["finish"]["finished"] == 4
    assert summary["tokens"] == {"prompt": 10, "completion": 4, "records": 1, "cost_usd": 0.0}
    assert summary["agents"] == ["llm", "oracle"]
    assert summary["by_agent"]["oracle"]["overall"]["passed_tasks"] == 1
    assert summary["by_agent"]["llm"]["overall"]["tasks"] == 3
    single = summarize(_trials("t1", [True]))
    assert "by_agent" not in single
    assert single["agents"] == ["oracle"]


def test_markdown_contains_headline_numbers_and_tables() -> None:
    records = _sanity_records()
    records[0]["checks"] = [_check("drone_altitude", True)]
    records[1]["level"] = "extreme"
    summary = summarize(records)
    text = render_markdown(summary, title="Run 7")
    assert text.startswith("# Run 7\n")
    assert "| Task Pass Rate | 70.3 % | 1054 / 1500 tasks |" in text
    assert "| Total Failed | 6.2 % | 93 / 1500 tasks |" in text
    assert "| Global Check | 82.0 % | 7383 / 9000 checks |" in text
    for heading in (
        "By family",
        "By level",
        "By category",
        "By template",
        "By check endpoint",
        "pass^k",
        "Finish reasons",
    ):
        assert f"## {heading}" in text
    assert "| drone_altitude | 1 | 1 | 100.0 % |" in text
    assert "| finished | 1500 | 100.0 % |" in text
    assert text.index("| easy |") < text.index("| extreme |")
    table = metrics_table(summary)
    assert table in text
    assert table.count("\n") == 5
    with pytest.raises(ValueError, match="summary field 'overall'"):
        metrics_table({})


def test_write_report_files(tmp_path: Path) -> None:
    levels = ["extreme", "easy", "hard"]
    records = [_rec(f"k{i}", level=level) for i, level in enumerate(levels)]
    md_path, json_path, html_path = write_report(records, tmp_path / "out")
    assert md_path == tmp_path / "out" / "report.md"
    assert json_path == tmp_path / "out" / "report.json"
    text = json_path.read_text(encoding="utf-8")
    loaded = json.loads(text)
    assert text == json.dumps(loaded, sort_keys=True, indent=2) + "\n"
    assert loaded == json.loads(json.dumps(summarize(records)))
    # Rendering the sorted-keys JSON still lists levels in difficulty order.
    rendered = render_markdown(loaded)
    assert md_path.read_text(encoding="utf-8") == rendered
    assert rendered.index("| easy |") < rendered.index("| hard |") < rendered.index("| extreme |")
    assert html_path == tmp_path / "out" / "report.html"
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [
        "report.html", "report.json", "report.md"]
