"""Every `mavswarm` error as a user meets it: one line on standard error, no traceback, exit
status 2, and nothing started. Busy ports (the real command in a subprocess, for every server),
missing and unusable files, bad values, a swarm bigger than this machine can run, and session
files with nothing to run (the command's `main` in this process: refused before anything
starts, they need no process of their own)."""

from __future__ import annotations

import contextlib
import json
import os
import socket
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest

from emulator.capacity import (
    CapacityError,
    Machine,
    check_capacity,
    network_memory_mb,
    process_networks,
)
from tests.bench_fixtures import small_session, write_json
from tests.cli_fixtures import MAVSWARM, run_in_process
from tests.ports import unused_tcp_port, unused_udp_port


def _mavswarm(*args: str, cwd: Path, timeout_s: float = 120.0
              ) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*MAVSWARM, *args], capture_output=True, text=True, cwd=cwd,
                          timeout=timeout_s, env={**os.environ, "PYTHONUNBUFFERED": "1"})


def _one_line_error(proc: subprocess.CompletedProcess[str], *needles: str) -> str:
    """The one line of standard error of a command that failed with status 2."""
    lines = proc.stderr.splitlines()
    assert proc.returncode == 2 and len(lines) == 1, (proc.returncode, proc.stderr,
                                                      proc.stdout[-2000:])
    (line,) = lines
    assert line.startswith("mavswarm") and "Traceback" not in proc.stdout + proc.stderr
    for needle in needles:
        assert needle in line, (needle, line)
    return line


@contextlib.contextmanager
def _busy_tcp_port() -> Iterator[int]:
    """A loopback TCP port another program listens on."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", unused_tcp_port()))
        sock.listen()
        yield sock.getsockname()[1]


def _results_folder(tmp_path: Path) -> Path:
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "results.jsonl").write_text("")
    return folder


def _quiet_up(*extra: str) -> list[str]:
    """`up` options that bind only ports of this test."""
    return ["up", "--no-truth", "--bind-host", "127.0.0.1", "--bind-port",
            str(unused_udp_port()), "--api-port", "0", "--gcs-port", "0", *extra]


def test_a_swarm_too_big_for_this_machine_is_refused_with_the_limits(tmp_path: Path) -> None:
    proc = run_in_process(*_quiet_up("--drones", "100000"), cwd=tmp_path)
    cores = len(os.sched_getaffinity(0))
    line = _one_line_error(proc, "--drones 100000 cannot run here", "system ids 1-250",
                           "400 networks", "10 processes of up to 10000 vehicles",
                           f"{cores} CPU core", "GB of memory available",
                           f"at most {min(cores, 10) * 10000} drones")
    assert proc.stdout == "", proc.stdout  # no network, no process started
    assert "one per core" in line


def test_capacity_per_process_and_per_machine() -> None:
    roomy = Machine(cores=4, memory_available_mb=64_000.0)
    assert check_capacity(250, roomy) == 1 and check_capacity(10_000, roomy) == 1
    assert check_capacity(10_001, roomy) == 2 and check_capacity(40_000, roomy) == 4
    with pytest.raises(CapacityError, match=r"161 networks .* 5 processes .* room for 4 "
                                            r"processes .* at most 40000 drones"):
        check_capacity(40_001, roomy)
    small = Machine(cores=64, memory_available_mb=3 * network_memory_mb(10_000) / 0.8 + 1)
    with pytest.raises(CapacityError, match=r"room for 3 processes .*at most 30000 drones"):
        check_capacity(40_000, small)
    starved = Machine(cores=8, memory_available_mb=50.0)
    with pytest.raises(CapacityError, match=r"--drones 5 cannot run here: this machine has 8 "
                                            r"CPU cores and 0.0 GB .* room for 0 processes"):
        check_capacity(5, starved)


def test_networks_are_shared_out_over_as_few_processes_as_hold_them() -> None:
    assert process_networks(250) == [range(0, 1)]
    assert process_networks(10_000) == [range(0, 40)]
    assert process_networks(10_001) == [range(0, 21), range(21, 41)]
    assert process_networks(25_000) == [range(0, 34), range(34, 67), range(67, 100)]


@pytest.mark.mavsdk
@pytest.mark.slow
def test_a_busy_port_is_one_line_for_every_server(tmp_path: Path) -> None:
    session = write_json(tmp_path / "s.json", small_session(["takeoff_hold"]))
    with _busy_tcp_port() as port:
        where = f"cannot listen on 127.0.0.1:{port}: address already in use"
        commands = {
            "replay": ["replay", str(_results_folder(tmp_path)), "--port", str(port)],
            "up --web": _quiet_up("--drones", "2", "--web", "--web-port", str(port)),
            "serve": ["serve", "--sessions", str(session), "--port", str(port)],
            "mcp": ["mcp", str(session), "--transport", "http", "--port", str(port)],
            "bench run --web": ["bench", "run", "--agent", "noop", "--sessions", str(session),
                                "--out", str(tmp_path / "out"), "--web", "--web-port",
                                str(port)],
        }
        for name, args in commands.items():
            proc = _mavswarm(*args, cwd=tmp_path)
            assert proc.returncode == 2, (name, proc.stderr)
            _one_line_error(proc, where)
    assert not (tmp_path / "out" / "results.jsonl").exists() or not (
        tmp_path / "out" / "results.jsonl").read_text()


@pytest.mark.parametrize(("args", "needles"), [
    (["replay", "/nonexistent/run"], ["/nonexistent/run"]),
    (["up", "--session", "/nonexistent/s.json"], ["/nonexistent/s.json"]),
    (["serve", "--sessions", "/nonexistent/s.json"], ["/nonexistent/s.json"]),
    (["bench", "run", "--agent", "noop", "--sessions", "/nonexistent/s.json"],
     ["/nonexistent/s.json", "cannot read"]),
    (["bench", "report", "/nonexistent/results.jsonl"], ["does not exist"]),
    (["bench", "import", "/nonexistent/ref.json", "--out", "imported"], ["/nonexistent"]),
    (["up", "--drones", "many"], ["mavswarm up: error: argument --drones", "--help"]),
    (["up", "--web", "--web-hz", "0"], ["--web-hz", "0.5 to 60"]),
    (["up", "--drones", "1", "--truth-out", "/proc/none/run.truth.npz"],
     ["--truth-out", "cannot make its folder"]),
    (["bench", "frob"], ["invalid choice: 'frob'"]),
    (["bench", "generate", "--workers", "0", "--out", "gen"], ["--workers", "at least 1"]),
    (["bench", "run", "--suite", "smoke", "--trials", "-1"], ["--trials", "at least 1"]),
    (["mqtt-bridge", "--mavlink", "bogus", "--mqtt", "mqtt://127.0.0.1:1"],
     ["cannot open the MAVLink connection 'bogus'"]),
])
def test_missing_files_and_bad_values_are_one_line(tmp_path: Path, args: list[str],
                                                   needles: list[str]) -> None:
    _one_line_error(run_in_process(*args, cwd=tmp_path), *needles)


def test_a_report_of_no_records_is_an_error(tmp_path: Path) -> None:
    torn = tmp_path / "results.jsonl"
    torn.write_text('{"key": "s/t01/noop/0", "pass')  # a killed run's only, torn line
    proc = run_in_process("bench", "report", str(torn), "--out", str(tmp_path / "rep"),
                          cwd=tmp_path)
    _one_line_error(proc, str(torn), "no task records to report")
    assert not (tmp_path / "rep").exists()


@pytest.mark.parametrize(("text", "needle"), [
    ('{"schema": "mavswarm.session/1", "id": ', "not valid JSON"),
    ("[1, 2]", "the top level must be a JSON object"),
    (json.dumps({**small_session([]), "tasks": []}), "the session has no tasks"),
])
def test_a_session_file_with_nothing_to_run_is_said_once(tmp_path: Path, text: str,
                                                         needle: str) -> None:
    session = tmp_path / "edited.json"
    session.write_text(text)
    proc = run_in_process("bench", "run", "--agent", "noop", "--sessions", str(session),
                          "--out", str(tmp_path / "out"), cwd=tmp_path)
    _one_line_error(proc, str(session), needle)
    assert "0 / 0" not in proc.stdout and "Task Pass Rate" not in proc.stdout
    assert not (tmp_path / "out").exists()  # nothing ran, nothing written
