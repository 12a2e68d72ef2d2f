"""`mavswarm bench`: run, report and import from the command line (a run in a real process;
bad arguments and an import through the command's `main` in this process)."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from tests.bench_fixtures import reference_session, small_session, write_json
from tests.cli_fixtures import MAVSWARM, run_in_process

ROOT = Path(__file__).resolve().parents[1]


def _mavswarm(*args: str, timeout: float = 120.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*MAVSWARM, *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=timeout)


@pytest.mark.mavsdk
def test_run_then_report(tmp_path: Path) -> None:
    session = write_json(tmp_path / "s.json", small_session(["takeoff_hold", "checkpoint"]))
    out = tmp_path / "out"
    run = _mavswarm("bench", "run", "--agent", "noop", "--sessions", str(session),
                    "--out", str(out))
    assert run.returncode == 0, run.stderr
    assert "Task Pass Rate" in run.stdout and "t02" in run.stdout
    assert (out / "report.md").exists() and (out / "results.jsonl").exists()
    summary = json.loads((out / "report.json").read_text())
    assert summary["overall"]["tasks"] == 2
    report = _mavswarm("bench", "report", str(out / "results.jsonl"), "--out",
                       str(tmp_path / "rep"))
    assert report.returncode == 0, report.stderr
    assert "Task Pass Rate" in report.stdout and (tmp_path / "rep" / "report.md").exists()


def test_bad_arguments_say_what_is_wrong(tmp_path: Path) -> None:
    agent = run_in_process("bench", "run", "--agent", "gpt-9", cwd=ROOT)
    assert agent.returncode == 2 and "gpt-9" in agent.stderr
    missing = run_in_process("bench", "run", "--agent", "noop", "--sessions",
                             str(tmp_path / "nope.json"), "--out", str(tmp_path / "o"), cwd=ROOT)
    assert missing.returncode == 2 and "nope.json" in missing.stderr
    corrupt = tmp_path / "bad.jsonl"
    corrupt.write_text('{"key": "a", "passed": true}\nnot json\n{"key": "b"}\n')
    report = run_in_process("bench", "report", str(corrupt), cwd=tmp_path)
    assert report.returncode == 2 and "bad.jsonl:2" in report.stderr


def test_import_command(tmp_path: Path) -> None:
    source = write_json(tmp_path / "ref.json", reference_session())
    result = run_in_process("bench", "import", str(source), "--out", str(tmp_path / "out"),
                            cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    written = list((tmp_path / "out").glob("*.json"))
    assert len(written) == 1
    data = json.loads(written[0].read_text())
    assert data["schema"] == "mavswarm.session/1" and len(data["drones"]) == 4
