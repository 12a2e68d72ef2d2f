"""A plug-in agent on a real Ray cluster (`ray start` nodes on loopback): the unit resolves the
spec from its text on the node, a relative file path from the directory the run started in."""

from __future__ import annotations

import importlib.util
import os
import subprocess
from pathlib import Path

import pytest

from benchmark.running.results import read_records
from tests.bench_fixtures import small_session, write_json
from tests.cli_fixtures import MAVSWARM
from tests.plugin_fixtures import write_plugins


@pytest.mark.skipif(importlib.util.find_spec("ray") is None,
                    reason="ray is not installed (pip install 'mavswarm[ray]')")
@pytest.mark.mavsdk
@pytest.mark.slow
def test_a_plugin_file_runs_as_ray_tasks(tmp_path: Path) -> None:
    from tests.ray_cluster import LocalRayCluster
    write_plugins(tmp_path)
    session = write_json(tmp_path / "s.json", small_session(["takeoff_hold", "checkpoint"]))
    out = tmp_path / "out"
    spec = "plugins_under_test.py:NoArguments"
    with LocalRayCluster(head_cpus=0) as cluster:
        cluster.add_node(num_cpus=1)
        run = subprocess.run([*MAVSWARM, "bench", "run", "--agent", spec, "--sessions",
                              str(session), "--out", str(out), "--backend", "ray",
                              "--ray-address", cluster.address],
                             cwd=tmp_path, env={**os.environ, **cluster.env},
                             capture_output=True, text=True, timeout=400)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    records = read_records(out / "results.jsonl")
    assert [(r["agent"], r["finish"], r["tool_calls"]) for r in records] == [
        (spec, "finished", 1)] * 2
