"""The shipped `mavswarm` command, as tests run it: the console script installed beside this
interpreter, or (`run_in_process`) its `main` in this process, for the commands whose answer
does not depend on being a process of their own (bad input refused before anything starts):
a subprocess costs seconds of interpreter and import start-up per call."""

from __future__ import annotations

import concurrent.futures
import contextlib
import io
import os
import subprocess
import sys
import time
from pathlib import Path

__all__ = ["MAVSWARM", "ROOT", "read_until", "run_in_process", "run_in_process_thread", "start_up"]

ROOT = Path(__file__).resolve().parents[1]
_SCRIPT = Path(sys.executable).with_name("mavswarm")
MAVSWARM: list[str] = [str(_SCRIPT)] if _SCRIPT.exists() else [sys.executable, "-m", "mavswarm"]
"""argv prefix of the `mavswarm` command."""


def start_up(*args: str) -> subprocess.Popen[str]:
    """`mavswarm up ARGS` in a subprocess, its stdout and stderr merged and unbuffered."""
    return subprocess.Popen(
        [*MAVSWARM, "up", *args],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )


def read_until(proc: subprocess.Popen[str], needle: str, timeout_s: float = 20.0) -> str:
    """Everything `proc` printed up to the line holding `needle` (AssertionError if it ends
    or `timeout_s` passes first)."""
    assert proc.stdout is not None
    seen = []
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        seen.append(line)
        if needle in line:
            return "".join(seen)
    raise AssertionError(f"{needle!r} not printed; got:\n{''.join(seen)}")


def run_in_process(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """`mavswarm ARGS` run by `mavswarm.cli.main` in this process, from `cwd`: its exit status
    and what it printed, as `subprocess.run(..., capture_output=True, text=True)` gives them.
    An exception the command lets out is raised here (a subprocess would print a traceback).
    Call it where no event loop runs (a plain `def` test): commands run their own."""
    from mavlink_gateway.mavsdk_log import mavsdk_log_enabled, set_mavsdk_log
    from mavswarm.cli import main

    out, err = io.StringIO(), io.StringIO()
    logging_before = mavsdk_log_enabled()  # main() sets it; the other tests keep theirs
    with contextlib.chdir(cwd), contextlib.redirect_stdout(out), \
            contextlib.redirect_stderr(err):
        try:
            status = main(list(args))
        except SystemExit as exit_:  # argparse's errors and --help
            status = exit_.code if isinstance(exit_.code, int) else 1
            if not isinstance(exit_.code, int | None):
                print(exit_.code, file=sys.stderr)
        finally:
            set_mavsdk_log(logging_before)
    return subprocess.CompletedProcess(["mavswarm", *args], status or 0, out.getvalue(),
                                       err.getvalue())


def run_in_process_thread(*args: str, cwd: Path, timeout_s: float = 300.0
                          ) -> subprocess.CompletedProcess[str]:
    """`run_in_process` on a thread of its own, for a caller whose thread holds an event loop
    (Playwright's sync API keeps one in the test's thread)."""
    with concurrent.futures.ThreadPoolExecutor(1) as runner:
        return runner.submit(run_in_process, *args, cwd=cwd).result(timeout=timeout_s)
