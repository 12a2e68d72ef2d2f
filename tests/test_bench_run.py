"""Benchmark runs against the real emulator over MAVLink: the oracle passes, the do-nothing
agent fails, runs resume after a kill without losing or duplicating a record, and results do
not depend on the machine's speed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from benchmark.running.orchestrator import RunPlan, run_benchmark
from benchmark.running.results import read_records
from tests.bench_fixtures import small_session, write_json

pytestmark = [pytest.mark.mavsdk, pytest.mark.slow]

KEYS = ["takeoff_hold", "round_trip_home", "climb_and_face", "new_home", "altitude_change"]


@pytest.fixture(scope="module")
def session_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("sessions")
    return write_json(folder / "s.json", small_session(KEYS))


@pytest.fixture(scope="module")
def oracle_run(session_file: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The oracle's run of the session, once for the tests that read it: its results folder."""
    out = tmp_path_factory.mktemp("oracle")
    _run(session_file, out)
    return out


def _verdicts(records: list[dict]) -> list[tuple]:
    return [(r["task"], r["passed"], tuple(c["passed"] for c in r["checks"]))
            for r in sorted(records, key=lambda r: r["task"])]


def _run(session: Path, out: Path, agent: str = "oracle", **kw: object) -> list[dict]:
    lines: list[str] = []
    run_benchmark(RunPlan(sessions=(session,), agent=agent, out_dir=out, **kw),  # type: ignore[arg-type]
                  progress=lines.append)
    return read_records(out / "results.jsonl")


def test_oracle_passes_every_task_and_noop_fails(session_file: Path, oracle_run: Path,
                                                 tmp_path: Path) -> None:
    records = read_records(oracle_run / "results.jsonl")
    assert [r["task"] for r in records] == [f"t0{k}" for k in range(1, 6)]
    failed = [(r["task"], [c for c in r["checks"] if not c["passed"]]) for r in records
              if not r["passed"]]
    assert not failed, failed
    for r in records:
        assert r["finish"] == "finished"
        assert r["checks_passed"] == r["checks_total"] > 0
        assert r["tool_calls"] >= 2 and r["sim_time_s"] > 0
        assert set(r["overhead_s"]) == {"reset", "evaluate"}
    noop = _run(session_file, tmp_path / "noop", agent="noop")
    assert not any(r["passed"] for r in noop)
    # Nothing flew: the window is the one simulated second every task ends with.
    assert all(r["tool_calls"] == 0 and r["sim_time_s"] == 1.0 for r in noop)


def test_resume_after_a_kill_loses_and_duplicates_nothing(session_file: Path, oracle_run: Path,
                                                          tmp_path: Path) -> None:
    whole = read_records(oracle_run / "results.jsonl")
    out = tmp_path / "killed"
    out.mkdir()
    lines = (oracle_run / "results.jsonl").read_text().splitlines(keepends=True)
    # As if killed while writing the third record: two whole lines and a torn one.
    (out / "results.jsonl").write_text("".join(lines[:2]) + lines[2][:57])
    resumed = _run(session_file, out)
    assert [r["key"] for r in resumed] == [r["key"] for r in whole]
    assert _verdicts(resumed) == _verdicts(whole)
    again = _run(session_file, out)  # nothing left to do
    assert len(again) == len(whole)


def test_two_workers_and_trials_give_the_same_scores(session_file: Path, tmp_path: Path) -> None:
    twin = write_json(tmp_path / "twin.json",
                      {**json.loads(session_file.read_text()), "id": "twin-session"})
    records = _run(session_file, tmp_path / "par", workers=2, trials=2)
    records += _run(twin, tmp_path / "par2")
    by_trial = {}
    for r in records:
        by_trial.setdefault((r["session"], r["trial"]), []).append(r)
    assert len(by_trial) == 3
    verdicts = {k: _verdicts(v) for k, v in by_trial.items()}
    first = next(iter(verdicts.values()))
    assert all(v == first for v in verdicts.values()), verdicts
