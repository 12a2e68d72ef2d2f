"""What `mavswarm bench run` and `bench generate` print: plain lines when standard output is
a pipe, a live progress bar under a terminal (a pseudo-terminal here), and no MAVSDK log
lines unless --verbose."""

from __future__ import annotations

import fcntl
import os
import pty
import re
import select
import struct
import subprocess
import termios
import time
from pathlib import Path

import pytest

from tests.bench_fixtures import small_session, write_json
from tests.cli_fixtures import MAVSWARM, ROOT

MAVSDK_LOG_LINE = re.compile(r"\[\d\d:\d\d:\d\d\|(Debug|Info|Warn|Error)\s*\]")
ESCAPE = "\x1b["
BAR = "\u2501"  # rich's bar segment


def _piped(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*MAVSWARM, *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=180, stdin=subprocess.DEVNULL)


def _in_terminal(*args: str, timeout_s: float = 180.0, columns: int = 120) -> tuple[int, str]:
    """Run `mavswarm ARGS` with a `columns` x 40 pseudo-terminal as stdout and stderr; its
    exit status and everything it wrote."""
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, columns, 0, 0))
    env = {name: value for name, value in os.environ.items()
           if name not in ("COLUMNS", "LINES", "NO_COLOR", "FORCE_COLOR", "TTY_COMPATIBLE",
                           "TTY_INTERACTIVE")}
    proc = subprocess.Popen([*MAVSWARM, *args], cwd=ROOT, stdin=subprocess.DEVNULL,
                            stdout=slave, stderr=slave, env={**env, "TERM": "xterm-256color"})
    os.close(slave)
    chunks: list[bytes] = []
    deadline = time.monotonic() + timeout_s
    try:
        while time.monotonic() < deadline:
            ready, _, _ = select.select([master], [], [], 0.5)
            if ready:
                try:
                    data = os.read(master, 65536)
                except OSError:  # the terminal closed: every writer has exited
                    break
                if not data:
                    break
                chunks.append(data)
            elif proc.poll() is not None:
                break
        else:
            proc.kill()
            raise AssertionError(f"no end within {timeout_s} s: {b''.join(chunks)[-2000:]!r}")
        return proc.wait(timeout=30), b"".join(chunks).decode("utf-8", "replace")
    finally:
        os.close(master)
        if proc.poll() is None:
            proc.kill()


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("sessions")
    return write_json(folder / "s.json", small_session(["takeoff_hold", "climb_and_face"]))


@pytest.mark.mavsdk
@pytest.mark.slow
def test_piped_run_prints_plain_lines_and_no_mavsdk_log(session: Path, tmp_path: Path) -> None:
    run = _piped("bench", "run", "--agent", "noop", "--sessions", str(session),
                 "--out", str(tmp_path / "out"))
    assert run.returncode == 0, run.stderr[-2000:]
    lines = run.stdout.splitlines()
    task_lines = [line for line in lines if re.match(r"\s+\d+ (PASS|fail)\b.* t0\d ", line)]
    assert len(task_lines) == 2, run.stdout
    assert all(" fail " in line for line in task_lines)
    assert ESCAPE not in run.stdout and BAR not in run.stdout
    both = run.stdout + run.stderr
    assert not MAVSDK_LOG_LINE.search(both) and ".cpp:" not in both, both[-3000:]
    assert (tmp_path / "out" / "report.html").exists()
    assert "report.html" in run.stdout


@pytest.mark.mavsdk
@pytest.mark.slow
def test_verbose_brings_mavsdk_log_back(session: Path, tmp_path: Path) -> None:
    run = _piped("bench", "run", "--agent", "noop", "--sessions", str(session),
                 "--out", str(tmp_path / "out"), "--verbose")
    assert run.returncode == 0, run.stderr[-2000:]
    assert MAVSDK_LOG_LINE.search(run.stdout + run.stderr), run.stdout[-3000:]


@pytest.mark.mavsdk
@pytest.mark.slow
def test_run_in_a_terminal_shows_a_progress_bar(session: Path, tmp_path: Path) -> None:
    status, text = _in_terminal("bench", "run", "--agent", "noop", "--sessions", str(session),
                                "--out", str(tmp_path / "out"))
    assert status == 0, text[-3000:]
    plain = re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", text)
    assert BAR in plain and "ETA" in plain
    assert re.search(r"tasks\s+\u2501+\s+2/2\s+pass\s+0\.0 %", plain), plain[-3000:]
    assert re.search(r"\s0/2\s", plain)  # drawn before the first task ended
    assert "t01" in plain and "takeoff_hold" in plain  # failed tasks are named above the bar
    assert not MAVSDK_LOG_LINE.search(plain)
    assert "Task Pass Rate" in plain


@pytest.mark.slow
def test_generate_prints_lines_when_piped_and_a_bar_in_a_terminal(tmp_path: Path) -> None:
    args = ("bench", "generate", "--no-verify", "--only", "area_search-easy-1")
    piped = _piped(*args, "--out", str(tmp_path / "a"))
    assert piped.returncode == 0, piped.stderr
    assert re.search(r"^generated .*area_search-easy-1\.json$", piped.stdout, re.M)
    assert ESCAPE not in piped.stdout and BAR not in piped.stdout
    status, text = _in_terminal(*args, "--out", str(tmp_path / "b"))
    assert status == 0, text
    plain = re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", text)
    assert re.search(r"sessions\s+\u2501+\s+1/1", plain), plain
    assert (tmp_path / "b" / "area_search-easy-1.json").exists()
