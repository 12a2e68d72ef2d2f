"""Progress of long benchmark work (`bench run`, `bench generate`) on the terminal.

On a terminal, a live rich progress bar: done / total, the pass rate so far (runs), elapsed
time and the time left; notes, errors and failed tasks are printed above it. When standard
output is not a terminal (a pipe, a file, CI, tests), one plain line per finished item and
per message instead, with no control codes.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Mapping
from types import TracebackType
from typing import Any, TextIO

from rich.console import Console
from rich.markup import escape
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TaskID,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

__all__ = ["LineProgress", "ProgressBar", "ProgressSink", "task_line"]


class ProgressSink:
    """What long work reports to: the total, each finished item, and messages. This base
    class prints nothing; see :class:`LineProgress` and :class:`ProgressBar`."""

    def begin(self, total: int, done: int = 0, passed: int = 0) -> None:
        """`total` items in all, of which `done` are already finished (`passed` of them
        passed)."""

    def advance(self, line: str, passed: bool | None = None) -> None:
        """One item finished; `line` describes it, `passed` its verdict (None: no verdict)."""

    def say(self, text: str) -> None:
        """A note or an error to show now."""


class LineProgress(ProgressSink):
    """One line per finished item and per message, handed to `emit` (default: print)."""

    def __init__(self, emit: Callable[[str], None] = print) -> None:
        self._emit = emit

    def advance(self, line: str, passed: bool | None = None) -> None:
        self._emit(line)

    def say(self, text: str) -> None:
        self._emit(text)


def _pass_rate(passed: int, done: int) -> str:
    return f"pass {100.0 * passed / done:5.1f} %" if done else "pass   -.- %"


class ProgressBar(ProgressSink):
    """A rich progress bar on `stream` (default: standard output) when it is a terminal,
    else :class:`LineProgress` lines on it. Use as a context manager around the work."""

    def __init__(self, unit: str, *, stream: TextIO | None = None,
                 pass_rate: bool = True) -> None:
        self.stream = stream if stream is not None else sys.stdout
        self.live = self.stream.isatty()
        self.unit = unit
        self._show_rate = pass_rate
        self._lines = LineProgress(lambda text: print(text, file=self.stream, flush=True))
        self._done = self._passed = 0
        self._progress: Progress | None = None
        self._task: TaskID | None = None

    def __enter__(self) -> ProgressBar:
        if self.live:
            console = Console(file=self.stream, force_terminal=True)
            columns = [TextColumn(f"[bold]{escape(self.unit)}[/]"), BarColumn(),
                       MofNCompleteColumn()]
            if self._show_rate:
                columns.append(TextColumn("{task.fields[rate]}"))
            columns += [TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn()]
            self._progress = Progress(*columns, console=console, transient=False)
            self._progress.start()
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 traceback: TracebackType | None) -> None:
        if self._progress is not None:
            self._progress.stop()
            self._progress = None

    def begin(self, total: int, done: int = 0, passed: int = 0) -> None:
        self._done, self._passed = done, passed
        if self._progress is not None:
            self._task = self._progress.add_task(
                self.unit, total=max(total, done), completed=done,
                rate=_pass_rate(passed, done))

    def advance(self, line: str, passed: bool | None = None) -> None:
        self._done += 1
        self._passed += passed is True
        if self._progress is None or self._task is None:
            self._lines.advance(line, passed)
            return
        if passed is False:
            self._progress.console.print(escape(line), style="red", highlight=False,
                                         no_wrap=True, overflow="ellipsis")
        task = self._progress.tasks[self._task]
        total = task.total if task.total is not None else 0
        self._progress.update(self._task, advance=1, total=max(total, self._done),
                              rate=_pass_rate(self._passed, self._done))

    def say(self, text: str) -> None:
        if self._progress is None:
            self._lines.say(text)
        else:
            self._progress.console.print(escape(text), highlight=False)


def task_line(record: Mapping[str, Any], n: int) -> str:
    """One finished task as a line: its verdict first (how it ended, if not by finishing, and
    its checks), then which task it was, its calls and times. A terminal too narrow for the
    whole line cuts its end, never the verdict."""
    verdict = "PASS" if record["passed"] else "fail"
    finish = f" [{record['finish']}]" if record["finish"] != "finished" else ""
    return (f"{n:5d} {verdict}{finish} {record['checks_passed']:>2}/{record['checks_total']:<2} "
            f"checks  {record['session']} {record['task']} {record['template']}  "
            f"{record['tool_calls']} calls {record['sim_time_s']:.0f} s sim "
            f"{record['wall_time_s']:.2f} s")
