"""Task records read back from results.jsonl are checked before resume or a report uses them:
a damaged line stops the read with its file and line and never counts as a new task. A real
resume (`mavswarm bench run` in a subprocess; the run before it and `bench report` by the
command's `main` in this process), and a seeded property-based fuzz of the reader."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from benchmark.running.episode import base_record, error_record
from benchmark.running.results import ResultsError, read_task_records
from benchmark.running.task_record import TaskRecord, record_key, record_problem
from tests.bench_fixtures import small_session, write_json
from tests.cli_fixtures import run_in_process

FUZZ = settings(derandomize=True, database=None, deadline=None, print_blob=True,
                suppress_health_check=list(HealthCheck), max_examples=400)
KNOWN = {"s1": frozenset({"t01", "t02", "t03"})}


def _mavswarm(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])}
    return subprocess.run([sys.executable, "-m", "mavswarm", *args], capture_output=True,
                          text=True, timeout=300, cwd=cwd, env=env)


def _records() -> list[dict[str, Any]]:
    """Three records as the episode writes them: two of tasks that ran (with the fields only
    a run adds), one of a task that could not run."""
    records = []
    for k, task in enumerate(["t01", "t02", "t03"]):
        base = base_record(session_id="s1", family="area_search", level="easy", task_id=task,
                           template="takeoff_hold", category="navigation", agent="oracle",
                           trial=0)
        record = error_record(base, "the session cannot start")
        if k < 2:
            record.update(passed=k == 0, finish="finished", error=None, clock="lockstep",
                          checks=[{"endpoint": "altitude", "passed": k == 0}],
                          checks_total=1, checks_passed=1 - k, tool_calls=3,
                          sim_time_s=12.5, wall_time_s=0.2,
                          tokens={"prompt": 10, "completion": 4, "cost_usd": 0.001},
                          end_state={"drones": {}}, window_s=[1.0, 13.5])
        records.append(record)
    return records


def _lines(records: list[dict[str, Any]]) -> list[bytes]:
    return [json.dumps(r).encode() + b"\n" for r in records]


def test_the_records_the_episode_writes_are_task_records() -> None:
    for record in _records():
        assert record_problem(record, KNOWN) is None, record
        assert TaskRecord.model_validate(record).key == record_key("s1", record["task"],
                                                                   "oracle", 0)


@pytest.mark.parametrize(("change", "problem"), [
    ({"key": "s1/t02/oracle/0#garbage#"}, "does not match its fields"),
    ({"trial": "0"}, "field 'trial'"),
    ({"passed": 1}, "field 'passed'"),
    ({"sim_time_s": -1.0}, "field 'sim_time_s'"),
    ({"checks_passed": 5}, "5 checks passed of 1"),
    ({"task": "t09", "key": "s1/t09/oracle/0"}, "task 't09', which session 's1' does not"),
    ({"session": "s9", "key": "s9/t02/oracle/0"}, "session 's9', which is not one of"),
])
def test_a_damaged_record_names_its_file_and_line(tmp_path: Path, change: dict[str, Any],
                                                  problem: str) -> None:
    records = _records()
    records[1] = {**records[1], **change}
    path = tmp_path / "results.jsonl"
    path.write_bytes(b"".join(_lines(records)))
    with pytest.raises(ResultsError) as raised:
        read_task_records(path, KNOWN)
    assert str(raised.value).startswith(f"{path}:2: ") and problem in str(raised.value)
    assert "\n" not in str(raised.value)


_FIELDS = sorted(_records()[0])
_JSON = st.recursive(st.none() | st.booleans() | st.integers() | st.floats() | st.text(),
                     lambda inner: st.lists(inner, max_size=3)
                     | st.dictionaries(st.text(max_size=5), inner, max_size=3), max_leaves=8)
_BYTES = st.binary(max_size=40).map(lambda b: b.replace(b"\n", b""))


@st.composite
def _mangled(draw: st.DrawFn) -> tuple[int, bytes]:
    """One line of the file (its index) made into something else, still one line."""
    records = _records()
    index = draw(st.integers(0, len(records) - 1))
    record = records[index]
    line = _lines(records)[index][:-1]
    how = draw(st.sampled_from(["key suffix", "set field", "drop field", "bytes", "splice",
                                "cut", "deep"]))
    if how == "key suffix":
        record["key"] += draw(st.text(min_size=1, max_size=12).filter(lambda s: "\n" not in s))
    elif how == "set field":
        record[draw(st.sampled_from(_FIELDS))] = draw(_JSON)
    elif how == "drop field":
        record.pop(draw(st.sampled_from(_FIELDS)), None)
    if how in ("key suffix", "set field", "drop field"):
        return index, json.dumps(record).encode()
    at = draw(st.integers(0, len(line)))
    if how == "bytes":
        return index, draw(_BYTES)
    if how == "splice":
        return index, line[:at] + draw(_BYTES) + line[at:]
    if how == "cut":
        return index, line[:at] + line[draw(st.integers(at, len(line))):]
    depth = draw(st.integers(1000, 100_000))
    return index, b"[" * depth + b"]" * depth


@FUZZ
@given(mangled=_mangled())
@pytest.mark.slow
def test_fuzzed_lines_never_crash_never_add_a_task_and_name_their_line(
        tmp_path_factory: pytest.TempPathFactory, mangled: tuple[int, bytes]) -> None:
    index, line = mangled
    lines = _lines(_records())
    lines[index] = line + b"\n"
    path = tmp_path_factory.mktemp("fuzz") / "results.jsonl"
    path.write_bytes(b"".join(lines))
    try:
        records = read_task_records(path, KNOWN)
    except ResultsError as error:
        assert str(error).startswith(f"{path}:{index + 1}: "), (str(error), line)
        return
    keys = [r["key"] for r in records]
    original = [r["key"] for r in _records()]
    assert set(keys) <= set(original) and len(keys) == len(set(keys)), keys
    assert all(record_problem(r, KNOWN) is None for r in records)


@pytest.mark.mavsdk
@pytest.mark.slow
def test_resume_stops_at_a_mangled_key_and_runs_nothing(tmp_path: Path) -> None:
    session = write_json(tmp_path / "s.json", small_session(["takeoff_hold", "climb_and_face"]))
    out = tmp_path / "out"
    args = ("bench", "run", "--agent", "noop", "--sessions", str(session), "--out", str(out))
    first = run_in_process(*args, cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    results = out / "results.jsonl"
    lines = results.read_text().splitlines(keepends=True)
    assert len(lines) == 2
    record = json.loads(lines[1])
    record["key"] += "#garbage#"
    damaged = lines[0] + json.dumps(record) + "\n"
    results.write_text(damaged)

    resumed = _mavswarm(*args, cwd=tmp_path)
    assert resumed.returncode == 2, (resumed.stdout, resumed.stderr)
    (message,) = resumed.stderr.splitlines()
    assert message.startswith(f"mavswarm: {results}:2: record key ")
    assert "does not match its fields" in message
    assert results.read_text() == damaged  # nothing run, nothing written

    report = run_in_process("bench", "report", str(results), "--out", str(tmp_path / "rep"),
                            cwd=tmp_path)
    assert report.returncode == 2 and report.stderr.startswith(f"mavswarm: {results}:2: ")
    assert len(report.stderr.splitlines()) == 1


def test_resume_refuses_a_record_of_a_task_the_sessions_do_not_have(tmp_path: Path) -> None:
    from benchmark.running.orchestrator import RunPlan, run_benchmark
    data = small_session(["takeoff_hold"])
    session = write_json(tmp_path / "s.json", data)
    records = _records()
    for record in records[:2]:
        record.update(session=data["id"], key=record_key(data["id"], record["task"],
                                                         "noop", 0), agent="noop")
    results = tmp_path / "out" / "results.jsonl"
    results.parent.mkdir()
    results.write_bytes(b"".join(_lines(records[:2])))  # t01 is the session's, t02 is not
    with pytest.raises(ResultsError, match=rf"^{results}:2: record '{data['id']}/t02/noop/0' "
                                           rf"names task 't02', which session"):
        run_benchmark(RunPlan(sessions=(session,), agent="noop", out_dir=tmp_path / "out"),
                      progress=lambda _: None)
    assert results.read_bytes() == b"".join(_lines(records[:2]))
