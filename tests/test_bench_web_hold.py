"""`mavswarm bench run --web` keeps its console open once the run is over, says so, and ends
on Ctrl-C; with --web-exit it ends with the run."""

from __future__ import annotations

import os
import signal
import subprocess
from pathlib import Path

import httpx
import pytest

from tests.bench_fixtures import small_session, write_json
from tests.cli_fixtures import MAVSWARM, read_until
from tests.ports import unused_tcp_port

pytestmark = [pytest.mark.mavsdk, pytest.mark.slow]


def _bench_web(tmp_path: Path, port: int, *extra: str) -> subprocess.Popen[str]:
    """The command as a shell script's background job starts it: with SIGINT ignored (`trap ''
    INT`), which the command undoes, since it ends on Ctrl-C."""
    session = write_json(tmp_path / "s.json", small_session(["takeoff_hold", "climb_and_face"]))
    command = [*MAVSWARM, "bench", "run", "--agent", "noop", "--sessions", str(session),
               "--out", str(tmp_path / "run"), "--web", "--web-port", str(port), "--web-key",
               "watch", *extra]
    return subprocess.Popen(
        ["sh", "-c", 'trap "" INT; exec "$@"', "sh", *command],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"})


def test_the_console_stays_open_after_the_run_until_ctrl_c(tmp_path: Path) -> None:
    port = unused_tcp_port()
    proc = _bench_web(tmp_path, port)
    try:
        printed = read_until(proc, "stays open", 180)
        assert "2 new task records" in printed
        assert f"http://127.0.0.1:{port}/?key=watch until Ctrl-C" in printed
        assert "--web-exit" in printed
        assert proc.poll() is None
        info = httpx.get(f"http://127.0.0.1:{port}/api/info", headers={"X-API-Key": "watch"})
        assert info.status_code == 200 and len(info.json()["live"]) == 1
        proc.send_signal(signal.SIGINT)
        assert proc.wait(90) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    with pytest.raises(httpx.ConnectError):
        httpx.get(f"http://127.0.0.1:{port}/api/info", timeout=2.0)


def test_web_exit_ends_with_the_run(tmp_path: Path) -> None:
    proc = _bench_web(tmp_path, unused_tcp_port(), "--web-exit")
    try:
        out, _ = proc.communicate(timeout=180)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    assert proc.returncode == 0, out
    assert "2 new task records" in out and "stays open" not in out
