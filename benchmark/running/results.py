"""Append-only JSON Lines log of benchmark results, one record per evaluated task.

Every record is a JSON object with a unique string ``"key"``. :class:`ResultsLog` appends a
record as one ``os.write`` of one line plus ``"\\n"`` to a file opened with ``O_APPEND``, then
flushes it to disk with ``os.fsync``, so a record either is on disk whole or not at all.

A run killed in the middle of a write can leave a torn last line: bytes without their final
newline, or a last line that is not valid JSON. :meth:`ResultsLog.open` truncates such a tail
away (counting the removed lines in :attr:`ResultsLog.repaired`) and :func:`read_records` skips
it. A line that cannot be read anywhere else in the file is corruption, reported as
:class:`ResultsError` with the file name and line number.

:func:`read_task_records` (resume, reports) also checks each record is a task record
(`benchmark.running.task_record`): its schema, a key made of its fields, and where the run's
sessions
are known, one of their tasks; the first line that is not stops the read, named by its number.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Any

from benchmark.running.task_record import KnownTasks, record_problem

__all__ = ["ResultsError", "ResultsLog", "read_all_records", "read_all_task_records",
           "read_records", "read_task_records"]


class ResultsError(ValueError):
    """Raised when a results file cannot be used (names file and line)."""


@dataclass(frozen=True)
class _Scan:
    """What reading a results file found: its records and where its intact part ends."""

    records: tuple[dict[str, Any], ...]
    intact_bytes: int
    torn_lines: int


def _parse_line(raw: bytes) -> Any:
    return json.loads(raw.decode("utf-8"))


def _scan(path: Path, data: bytes,
          check: Callable[[Mapping[str, Any]], str | None] | None = None) -> _Scan:
    """Parse ``data`` (the bytes of ``path``); the torn tail, if any, is left out. ``check``
    says what is wrong with a record (None: nothing), line by line in file order."""
    torn_lines = 0
    intact_bytes = data.rfind(b"\n") + 1
    if intact_bytes < len(data):
        torn_lines += 1
    lines = data[:intact_bytes].split(b"\n")[:-1]
    parsed: list[tuple[int, Any]] = []
    for index, raw in enumerate(lines):
        line_no = index + 1
        if not raw.strip():
            continue
        try:
            value = _parse_line(raw)
        except (ValueError, RecursionError) as exc:  # bad UTF-8 or JSON, 5,000 digits, [[[...
            if index == len(lines) - 1:
                intact_bytes -= len(raw) + 1
                torn_lines += 1
                break
            raise ResultsError(f"{path}:{line_no}: corrupt results line ({exc})") from exc
        parsed.append((line_no, value))

    records: list[dict[str, Any]] = []
    seen: set[str] = set()
    for line_no, value in parsed:
        if not isinstance(value, dict):
            raise ResultsError(
                f"{path}:{line_no}: a results line must be a JSON object, "
                f"got {type(value).__name__}"
            )
        key = value.get("key")
        if not isinstance(key, str) or not key:
            raise ResultsError(
                f"{path}:{line_no}: record field 'key' must be a non-empty string, got {key!r}"
            )
        problem = check(value) if check is not None else None
        if problem is not None:
            raise ResultsError(f"{path}:{line_no}: {problem}")
        if key in seen:
            raise ResultsError(f"{path}:{line_no}: duplicate record key {key!r}")
        seen.add(key)
        records.append(value)
    return _Scan(tuple(records), intact_bytes, torn_lines)


def _encode(record: Mapping[str, Any]) -> tuple[str, bytes]:
    if not isinstance(record, Mapping):
        raise ValueError(f"a results record must be a mapping, got {type(record).__name__}")
    if "key" not in record:
        raise ValueError("results record has no 'key' field")
    key = record["key"]
    if not isinstance(key, str) or not key:
        raise ValueError(f"results record field 'key' must be a non-empty string, got {key!r}")
    try:
        text = json.dumps(dict(record), ensure_ascii=False, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"results record {key!r} is not JSON-serialisable: {exc}") from exc
    return key, (text + "\n").encode("utf-8")


class ResultsLog:
    """An append-only results file that remembers which task keys it already holds."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.repaired = 0
        self._keys: set[str] = set()
        self._fd: int | None = None

    @property
    def is_open(self) -> bool:
        """Whether :meth:`open` has run and :meth:`close` has not."""
        return self._fd is not None

    @property
    def keys(self) -> frozenset[str]:
        """Keys of every record in the file (as read by :meth:`open`, plus appended ones)."""
        return frozenset(self._keys)

    def __contains__(self, key: object) -> bool:
        return key in self._keys

    def open(self) -> set[str]:
        """Create the file if needed, cut off a torn last line, and return the recorded keys.

        Raises :class:`ResultsError` when a line before the last one is corrupt.
        """
        if self._fd is not None:
            raise RuntimeError(f"results log {self.path} is already open")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(self.path, os.O_RDWR | os.O_APPEND | os.O_CREAT, 0o644)
        try:
            with open(fd, "rb", closefd=False) as handle:
                data = handle.read()
            scan = _scan(self.path, data)
            if scan.intact_bytes < len(data):
                os.ftruncate(fd, scan.intact_bytes)
                os.fsync(fd)
        except BaseException:
            os.close(fd)
            raise
        self._fd = fd
        self.repaired = scan.torn_lines
        self._keys = {record["key"] for record in scan.records}
        return set(self._keys)

    def append(self, record: Mapping[str, Any]) -> None:
        """Write ``record`` as one line and sync it to disk.

        Raises ``ValueError`` for a record without a string ``"key"``, one whose key is already
        recorded, or one that cannot be written as JSON.
        """
        if self._fd is None:
            raise RuntimeError(f"results log {self.path} is not open; call open() first")
        key, line = _encode(record)
        if key in self._keys:
            raise ValueError(f"results record key {key!r} is already recorded in {self.path}")
        written = os.write(self._fd, line)
        while written < len(line):
            # Only a full disk or a signal interrupts a regular-file write; finish the line.
            written += os.write(self._fd, line[written:])
        os.fsync(self._fd)
        self._keys.add(key)

    def close(self) -> None:
        """Close the file; closing twice is harmless."""
        if self._fd is not None:
            fd, self._fd = self._fd, None
            os.close(fd)

    def __enter__(self) -> ResultsLog:
        self.open()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()


def _read(file_path: Path,
          check: Callable[[Mapping[str, Any]], str | None] | None = None) -> _Scan:
    try:
        data = file_path.read_bytes()
    except FileNotFoundError as exc:
        raise ResultsError(f"{file_path}: results file does not exist") from exc
    return _scan(file_path, data, check)


def read_records(path: str | Path) -> list[dict[str, Any]]:
    """All complete records of one results file, in file order; a torn last line is ignored."""
    return list(_read(Path(path)).records)


def read_task_records(path: str | Path, known: KnownTasks | None = None
                      ) -> list[dict[str, Any]]:
    """`read_records`, each record checked to be a task record (of the tasks `known`, a
    session id -> its task ids, if given); the first that is not raises ResultsError with
    the file and line."""
    return list(_read(Path(path), lambda record: record_problem(record, known)).records)


def read_all_records(paths: Iterable[str | Path]) -> list[dict[str, Any]]:
    """Records of several results files in order; a key seen in an earlier file wins."""
    seen: set[str] = set()
    records: list[dict[str, Any]] = []
    for path in paths:
        for record in read_records(path):
            if record["key"] not in seen:
                seen.add(record["key"])
                records.append(record)
    return records


def read_all_task_records(paths: Iterable[str | Path]) -> list[dict[str, Any]]:
    """`read_all_records` of task records (see `read_task_records`)."""
    seen: set[str] = set()
    records: list[dict[str, Any]] = []
    for path in paths:
        for record in read_task_records(path):
            if record["key"] not in seen:
                seen.add(record["key"])
                records.append(record)
    return records
