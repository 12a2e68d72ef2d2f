"""Plug-in agents through the `mavswarm` command, in real processes: the scripted example on
the smoke suite in two worker processes, an agent that an installed distribution registers
under the `mavswarm.agents` entry-point group; and bad specs refused in one line (the command's
`main` in this process: nothing starts)."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

import pytest

from benchmark.authoring.suite import suite_paths
from tests.bench_fixtures import small_session, write_json
from tests.cli_fixtures import MAVSWARM, run_in_process
from tests.plugin_fixtures import write_plugins

ROOT = Path(__file__).resolve().parents[1]
SCRIPTED = "examples/scripted_agent.py:ScriptedAgent"

TINY_AGENT = '''
class TinyAgent:
    """Launches the first drone, then finishes."""

    async def run(self, task, tools):
        await tools.take_off(tools.drone_ids[0], 6.0)
        tools.finish("launched")
'''


def _mavswarm(*args: str, cwd: Path = ROOT, path: list[Path] | None = None,
              timeout: float = 300.0) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ)
    if path:
        env["PYTHONPATH"] = os.pathsep.join([*map(str, path), env.get("PYTHONPATH", "")])
    return subprocess.run([*MAVSWARM, *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=timeout)


def _records(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]


@pytest.mark.mavsdk
@pytest.mark.slow
def test_the_scripted_example_runs_the_smoke_suite_in_workers(tmp_path: Path) -> None:
    out = tmp_path / "out"
    run = _mavswarm("bench", "run", "--agent", SCRIPTED, "--suite", "smoke", "--workers", "2",
                    "--out", str(out))
    assert run.returncode == 0, run.stderr
    records = _records(out)
    paths, limit = suite_paths("smoke")
    assert len(records) == len(paths) * (limit or 0) == 18
    assert {r["agent"] for r in records} == {SCRIPTED}
    assert [r["finish"] for r in records] == ["finished"] * 18, [r["error"] for r in records]
    # every drone took off and looked around (3 drones: take_off and nearby each, at least)
    assert all(r["tool_calls"] >= 6 and r["sim_time_s"] > 5.0 for r in records)
    assert any(r["passed"] for r in records)  # fleet take-offs pass
    assert json.loads((out / "report.json").read_text())["overall"]["tasks"] == 18


def _install_tiny_distribution(site: Path) -> None:
    """What `pip install` leaves for a package declaring
    [project.entry-points."mavswarm.agents"] tiny = "tiny_agent:TinyAgent"."""
    (site / "tiny_agent").mkdir(parents=True)
    (site / "tiny_agent" / "__init__.py").write_text(TINY_AGENT)
    info = site / "tiny_agent-0.3.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: tiny-agent\nVersion: 0.3\n")
    (info / "entry_points.txt").write_text("[mavswarm.agents]\ntiny = tiny_agent:TinyAgent\n"
                                           "noop = tiny_agent:TinyAgent\n")
    (info / "RECORD").write_text("")


@pytest.mark.mavsdk
def test_an_installed_entry_point_is_listed_and_runs(tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    site = tmp_path / "site"
    _install_tiny_distribution(site)
    session = write_json(tmp_path / "s.json", small_session(["takeoff_hold", "checkpoint"]))
    # A fresh `mavswarm` process finds the distribution and runs its agent.
    out = tmp_path / "out"
    run = _mavswarm("bench", "run", "--agent", "tiny", "--sessions", str(session),
                    "--out", str(out), path=[site])
    assert run.returncode == 0, run.stderr
    records = _records(out)
    assert [(r["agent"], r["finish"], r["tool_calls"]) for r in records] == [
        ("tiny", "finished", 1)] * 2

    # The listing and the built-in's precedence by the command's `main` in this process, with
    # and then without the distribution on the path.
    assert "tiny" not in run_in_process("bench", "agents", cwd=tmp_path).stdout.split()
    monkeypatch.syspath_prepend(str(site))
    listed = run_in_process("bench", "agents", cwd=tmp_path)
    assert listed.returncode == 0, listed.stderr
    lines = {line.split()[0]: line for line in listed.stdout.splitlines() if line.strip()}
    assert "built-in" in lines["oracle"] and "built-in" in lines["react"]
    assert "plug-in: tiny-agent 0.3" in lines["tiny"]
    assert "entry point tiny_agent:TinyAgent" in lines["tiny"]
    assert "tiny_agent:TinyAgent (hidden by the built-in of that name)" in listed.stdout
    # a plug-in named like a built-in does not replace it
    noop = run_in_process("bench", "run", "--agent", "noop", "--sessions", str(session),
                          "--out", str(tmp_path / "noop"), cwd=tmp_path)
    assert noop.returncode == 0, noop.stderr
    assert {r["tool_calls"] for r in _records(tmp_path / "noop")} == {0}


def test_bad_specs_are_one_line_and_exit_2_before_anything_starts(tmp_path: Path) -> None:
    plugins = write_plugins(tmp_path)
    (tmp_path / "crashes.py").write_text("raise ImportError('needs torch')\n")
    cases = {"gpt-9": "unknown agent 'gpt-9'",
             "crashes.py:Agent": "ImportError: needs torch (crashes.py:1)",
             f"{plugins.name}:SyncRun": "not `async def`",
             f"{plugins.name}:Missing": "has no 'Missing'",
             "no_such_package_xyz:Agent": "No module named 'no_such_package_xyz'"}
    for spec, reason in cases.items():
        out = tmp_path / "out"
        run = run_in_process("bench", "run", "--agent", spec, "--sessions", "whatever.json",
                             "--out", str(out), cwd=tmp_path)
        assert run.returncode == 2, (spec, run.stderr)
        assert run.stderr.count("\n") == 1 and reason in run.stderr, (spec, run.stderr)
        assert run.stdout == "" and not out.exists(), spec
    for bad in ("0", "-5", "nan"):
        run = run_in_process("bench", "run", "--agent", "noop", "--agent-timeout-s", bad,
                             "--sessions", "whatever.json", cwd=tmp_path)
        assert run.returncode == 2 and "--agent-timeout-s must be > 0" in run.stderr, bad
