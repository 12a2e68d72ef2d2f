"""Tests for the append-only JSON Lines results log."""

from __future__ import annotations

import json
import multiprocessing
from pathlib import Path
from typing import Any

import pytest

from benchmark.running.results import ResultsError, ResultsLog, read_all_records, read_records


def _record(key: str, **extra: Any) -> dict[str, Any]:
    return {"key": key, "passed": True, "checks_total": 1, "checks_passed": 1, **extra}


def _line(record: dict[str, Any]) -> str:
    return json.dumps(record) + "\n"


def test_open_creates_parent_directories_and_empty_file(tmp_path: Path) -> None:
    path = tmp_path / "a" / "b" / "results.jsonl"
    with ResultsLog(path) as log:
        assert log.keys == frozenset()
        assert log.repaired == 0
    assert path.exists()
    assert path.read_bytes() == b""


def test_append_writes_one_line_per_record_and_reopen_sees_keys(tmp_path: Path) -> None:
    path = tmp_path / "results.jsonl"
    log = ResultsLog(path)
    assert log.open() == set()
    log.append(_record("s/t01/oracle/0", note="héllo"))
    log.append(_record("s/t02/oracle/0"))
    assert "s/t01/oracle/0" in log
    log.close()
    text = path.read_text(encoding="utf-8")
    assert text.endswith("\n")
    assert len(text.splitlines()) == 2
    assert json.loads(text.splitlines()[0])["note"] == "héllo"

    reopened = ResultsLog(path)
    assert reopened.open() == {"s/t01/oracle/0", "s/t02/oracle/0"}
    assert reopened.repaired == 0
    reopened.close()
    assert [r["key"] for r in read_records(path)] == ["s/t01/oracle/0", "s/t02/oracle/0"]


def test_duplicate_key_is_refused_in_session_and_after_reopen(tmp_path: Path) -> None:
    path = tmp_path / "results.jsonl"
    with ResultsLog(path) as log:
        log.append(_record("k1"))
        with pytest.raises(ValueError, match="'k1' is already recorded"):
            log.append(_record("k1", passed=False))
    with ResultsLog(path) as log, pytest.raises(ValueError, match="already recorded"):
        log.append(_record("k1"))
    assert len(read_records(path)) == 1
    assert read_records(path)[0]["passed"] is True


@pytest.mark.parametrize(
    ("record", "message"),
    [
        ({"passed": True}, "no 'key' field"),
        ({"key": 7}, "'key' must be a non-empty string, got 7"),
        ({"key": ""}, "'key' must be a non-empty string"),
        ({"key": "nan", "value": float("nan")}, "'nan' is not JSON-serialisable"),
        ({"key": "obj", "value": object()}, "'obj' is not JSON-serialisable"),
    ],
)
def test_bad_records_are_refused_without_writing(
    tmp_path: Path, record: dict[str, Any], message: str
) -> None:
    path = tmp_path / "results.jsonl"
    with ResultsLog(path) as log:
        with pytest.raises(ValueError, match=message):
            log.append(record)
        assert log.keys == frozenset()
    assert path.read_bytes() == b""


def test_append_requires_open(tmp_path: Path) -> None:
    log = ResultsLog(tmp_path / "results.jsonl")
    with pytest.raises(RuntimeError, match="not open"):
        log.append(_record("k"))
    log.open()
    log.close()
    log.close()
    assert not log.is_open
    with pytest.raises(RuntimeError, match="not open"):
        log.append(_record("k"))


def test_torn_partial_line_is_truncated_on_open(tmp_path: Path) -> None:
    path = tmp_path / "results.jsonl"
    first = _line(_record("done"))
    path.write_text(first + '{"key": "torn", "passed": tr', encoding="utf-8")

    assert [r["key"] for r in read_records(path)] == ["done"]
    assert path.read_text(encoding="utf-8").endswith("tr"), "read_records must not modify"

    log = ResultsLog(path)
    assert log.open() == {"done"}
    assert log.repaired == 1
    assert path.read_text(encoding="utf-8") == first
    log.append(_record("torn"))
    log.close()
    assert [r["key"] for r in read_records(path)] == ["done", "torn"]


def test_complete_last_line_with_invalid_json_is_truncated(tmp_path: Path) -> None:
    path = tmp_path / "results.jsonl"
    first = _line(_record("a"))
    path.write_bytes(first.encode() + b"\x00\x00\x00\x00\n")
    assert [r["key"] for r in read_records(path)] == ["a"]
    with ResultsLog(path) as log:
        assert log.keys == {"a"}
        assert log.repaired == 1
    assert path.read_bytes() == first.encode()


def test_torn_line_that_is_the_whole_file_leaves_it_empty(tmp_path: Path) -> None:
    path = tmp_path / "results.jsonl"
    path.write_text('{"key": "x"', encoding="utf-8")
    with ResultsLog(path) as log:
        assert log.keys == frozenset()
        assert log.repaired == 1
    assert path.read_bytes() == b""


def test_corrupt_middle_line_names_file_and_line(tmp_path: Path) -> None:
    path = tmp_path / "results.jsonl"
    content = _line(_record("a")) + "{not json}\n" + _line(_record("b"))
    path.write_text(content, encoding="utf-8")
    with pytest.raises(ResultsError, match=r"results\.jsonl:2: corrupt results line"):
        read_records(path)
    log = ResultsLog(path)
    with pytest.raises(ResultsError, match=r"results\.jsonl:2:"):
        log.open()
    assert not log.is_open
    assert path.read_text(encoding="utf-8") == content


@pytest.mark.parametrize(
    ("second_line", "message"),
    [
        ('["a", "list"]\n', r":2: a results line must be a JSON object, got list"),
        ('{"passed": true}\n', r":2: record field 'key' must be a non-empty string, got None"),
        (_line(_record("a")), r":2: duplicate record key 'a'"),
    ],
)
def test_unusable_lines_raise_results_error(tmp_path: Path, second_line: str, message: str) -> None:
    path = tmp_path / "results.jsonl"
    path.write_text(_line(_record("a")) + second_line + _line(_record("c")), encoding="utf-8")
    with pytest.raises(ResultsError, match=message):
        read_records(path)


def test_blank_lines_are_skipped(tmp_path: Path) -> None:
    path = tmp_path / "results.jsonl"
    path.write_text(_line(_record("a")) + "\n" + _line(_record("b")), encoding="utf-8")
    assert [r["key"] for r in read_records(path)] == ["a", "b"]


def test_read_records_of_missing_file(tmp_path: Path) -> None:
    with pytest.raises(ResultsError, match="does not exist"):
        read_records(tmp_path / "nope.jsonl")


def test_read_all_records_keeps_first_of_repeated_keys(tmp_path: Path) -> None:
    first, second = tmp_path / "one.jsonl", tmp_path / "two.jsonl"
    first.write_text(_line(_record("a")) + _line(_record("b")), encoding="utf-8")
    second.write_text(_line(_record("b", passed=False)) + _line(_record("c")), encoding="utf-8")
    records = read_all_records([first, second])
    assert [r["key"] for r in records] == ["a", "b", "c"]
    assert records[1]["passed"] is True


_WORKERS = 4
_PER_WORKER = 40
_PAD = "x" * 9000  # longer than PIPE_BUF and a page, so interleaving would show


def _append_worker(path: str, worker: int, barrier: Any) -> None:
    log = ResultsLog(path)
    log.open()
    barrier.wait()
    for index in range(_PER_WORKER):
        log.append(_record(f"w{worker}/{index}", worker=worker, index=index, pad=_PAD))
    log.close()


@pytest.mark.slow
def test_concurrent_appends_from_processes_keep_every_line_intact(tmp_path: Path) -> None:
    path = tmp_path / "results.jsonl"
    context = multiprocessing.get_context("spawn")
    barrier = context.Barrier(_WORKERS)
    processes = [
        context.Process(target=_append_worker, args=(str(path), worker, barrier))
        for worker in range(_WORKERS)
    ]
    for process in processes:
        process.start()
    for process in processes:
        process.join(timeout=60)
        assert process.exitcode == 0

    lines = path.read_text(encoding="utf-8").split("\n")
    assert lines[-1] == ""
    assert len(lines) - 1 == _WORKERS * _PER_WORKER
    for line in lines[:-1]:
        record = json.loads(line)
        assert record["pad"] == _PAD
        assert record["key"] == f"w{record['worker']}/{record['index']}"
    keys = {r["key"] for r in read_records(path)}
    assert keys == {f"w{w}/{i}" for w in range(_WORKERS) for i in range(_PER_WORKER)}
