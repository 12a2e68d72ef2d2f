"""The Ray backend on a real Ray cluster of `ray start` nodes on loopback. A run writes the
records the local backend writes; a node killed mid-run loses and duplicates no record, its
sessions go on from where they stopped on a node that joins later, and a rerun resumes to
nothing left; generation on Ray writes the files a local one writes. Without Ray, the local
backend imports none of it and asking for Ray says how to install it."""

from __future__ import annotations

import importlib.util
import json
import os
import re
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from benchmark.running.backends import BackendUnavailable, make_backend
from benchmark.running.orchestrator import RunPlan, run_benchmark
from benchmark.running.results import read_records
from tests.bench_fixtures import small_session, write_json
from tests.cli_fixtures import MAVSWARM, ROOT
from tests.plugin_fixtures import write_plugins
from tests.scripted_llm import call, scripted_llm

# Three tasks a session: the node dies while each session holds its second, so each has one
# task recorded before and one after the one it was running.
KEYS = ["takeoff_hold", "climb_and_face", "altitude_change"]
RUN_TIMEOUT_S = 400.0


needs_ray = pytest.mark.skipif(
    importlib.util.find_spec("ray") is None,
    reason="ray is not installed (pip install 'mavswarm[ray]'; the dev extra installs it)")


@pytest.fixture(scope="module")
def cluster() -> Iterator[Any]:
    from tests.ray_cluster import LocalRayCluster
    # Sessions run on the worker nodes only (the head has no CPU for them): a killed node
    # takes every running session with it.
    with LocalRayCluster(head_cpus=0) as local_cluster:
        local_cluster.add_node(num_cpus=2)
        yield local_cluster


@pytest.fixture(scope="module")
def sessions(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, ...]:
    folder = tmp_path_factory.mktemp("sessions")
    return tuple(write_json(folder / f"s{k}.json", small_session(KEYS, index=k + 1, seed=k))
                 for k in range(2))


@pytest.fixture(scope="module")
def local_records(sessions: tuple[Path, ...], tmp_path_factory: pytest.TempPathFactory
                  ) -> list[dict[str, Any]]:
    out = tmp_path_factory.mktemp("local")
    # One worker: in this process (verdicts do not depend on workers, test_bench_run.py).
    run_benchmark(RunPlan(sessions=sessions, out_dir=out, workers=1), progress=lambda _: None)
    return read_records(out / "results.jsonl")


def _verdicts(records: list[dict[str, Any]]) -> dict[str, tuple[Any, ...]]:
    return {r["key"]: (r["passed"], r["finish"], r["checks_total"],
                       tuple(c["passed"] for c in r["checks"])) for r in records}


def _bench(cluster: Any, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen([*MAVSWARM, "bench", *args, "--backend", "ray",
                             "--ray-address", cluster.address],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, env={**os.environ, **cluster.env})


def _finish(proc: subprocess.Popen[str]) -> str:
    try:
        output, _ = proc.communicate(timeout=RUN_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        proc.kill()
        output, _ = proc.communicate()
        raise AssertionError(f"the run did not end:\n{output[-4000:]}") from None
    assert proc.returncode == 0, output[-4000:]
    return output


def _lines(path: Path) -> int:
    try:
        return path.read_bytes().count(b"\n")
    except FileNotFoundError:
        return 0


@needs_ray
@pytest.mark.mavsdk
@pytest.mark.slow
def test_a_ray_run_writes_what_the_local_backend_writes(
        cluster: Any, sessions: tuple[Path, ...], local_records: list[dict[str, Any]],
        tmp_path: Path) -> None:
    out = tmp_path / "ray"
    output = _finish(_bench(cluster, "run", "--agent", "oracle", "--workers", "1",
                            "--sessions", *map(str, sessions), "--out", str(out)))
    records = read_records(out / "results.jsonl")
    assert len(records) == len(sessions) * len(KEYS)
    assert _verdicts(records) == _verdicts(local_records), output[-4000:]
    assert all(r["passed"] for r in records)
    assert "as Ray tasks at " + cluster.address in output
    # One worker: one session at a time, though the node has a CPU for each.
    order = [r["session"] for r in records]
    assert order == sorted(order, key=order.index), order


@needs_ray
@pytest.mark.mavsdk
@pytest.mark.slow
def test_a_plugin_file_runs_as_ray_tasks(cluster: Any, tmp_path: Path) -> None:
    """The unit resolves the spec from its text on the node, a relative file path from the
    directory the run started in."""
    write_plugins(tmp_path)
    session = write_json(tmp_path / "s.json", small_session(["takeoff_hold", "checkpoint"]))
    out = tmp_path / "out"
    spec = "plugins_under_test.py:NoArguments"
    run = subprocess.run([*MAVSWARM, "bench", "run", "--agent", spec, "--sessions",
                          str(session), "--out", str(out), "--backend", "ray",
                          "--ray-address", cluster.address],
                         cwd=tmp_path, env={**os.environ, **cluster.env},
                         capture_output=True, text=True, timeout=RUN_TIMEOUT_S)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "as Ray tasks at " + cluster.address in run.stdout + run.stderr
    records = read_records(out / "results.jsonl")
    assert [(r["agent"], r["finish"], r["tool_calls"]) for r in records] == [
        (spec, "finished", 1)] * 2


_DRONES = re.compile(r"Your drones: ([^.]+)\.")


def _take_off_then_finish(request: dict[str, Any]) -> list[dict[str, Any]]:
    """A model that takes the task's first drone up to 10 m, then calls finish: the same
    reply to the same conversation, whichever session asks and in whichever order."""
    messages = request["messages"]
    if any(m["role"] == "tool" for m in messages):
        return [call("finish", {"summary": "done"})]
    drones = _DRONES.search(messages[1]["content"])
    assert drones is not None, messages[1]
    return [call("take_off", {"drone_id": drones.group(1).split(", ")[0], "altitude_m": 10})]


class _SecondTaskGate:
    """Holds every model request of each session's second task until opened: a session
    whose first task is recorded then waits on its model, mid-run, for as long as it takes."""

    def __init__(self, sessions: tuple[Path, ...]) -> None:
        self.texts = {json.loads(p.read_text())["tasks"][1]["text"] for p in sessions}
        self.opened = threading.Event()
        self.held: set[str] = set()
        self._lock = threading.Lock()

    def __call__(self, request: dict[str, Any]) -> None:
        task = request["messages"][1]["content"].split("\n")[0].removeprefix("Task: ")
        if task in self.texts and not self.opened.is_set():
            with self._lock:
                self.held.add(task)
            self.opened.wait()

    def holds_every_session(self) -> bool:
        with self._lock:
            return self.held == self.texts


@needs_ray
@pytest.mark.mavsdk
@pytest.mark.slow
def test_a_node_killed_mid_run_loses_and_duplicates_no_record(
        cluster: Any, sessions: tuple[Path, ...], tmp_path: Path) -> None:
    node = cluster.nodes[-1]
    assert node.alive and node is not cluster.nodes[0]
    gate = _SecondTaskGate(sessions)
    assert len(gate.texts) == len(sessions)
    with scripted_llm([], answer=_take_off_then_finish) as llm:
        run_benchmark(RunPlan(sessions=sessions, out_dir=tmp_path / "local", workers=1,
                              agent="react", model="scripted", base_url=llm.base_url),
                      progress=lambda _: None)
    local_records = read_records(tmp_path / "local" / "results.jsonl")
    assert len(local_records) == len(sessions) * len(KEYS)
    out = tmp_path / "ray"
    with scripted_llm([], answer=_take_off_then_finish, hold=gate) as llm:
        args = ("run", "--agent", "react", "--model", "scripted", "--base-url", llm.base_url,
                "--workers", "2", "--sessions", *map(str, sessions), "--out", str(out))
        proc = _bench(cluster, *args)
        try:
            # Both sessions run on the one worker node: each has its first task recorded and
            # waits on the model in its second when the node dies.
            deadline = time.monotonic() + RUN_TIMEOUT_S
            while _lines(out / "results.jsonl") < len(sessions) or not gate.holds_every_session():
                assert proc.poll() is None and time.monotonic() < deadline, \
                    proc.communicate()[0]
                time.sleep(0.05)
            node.kill()
            assert _lines(out / "results.jsonl") == len(sessions)
        finally:
            gate.opened.set()
        cluster.add_node(num_cpus=2)  # where the lost sessions go on
        output = _finish(proc)
        assert output.count("running it again after its 1 recorded task(s)") == len(sessions), \
            output[-4000:]
        records = read_records(out / "results.jsonl")  # raises on a duplicate key
        assert _verdicts(records) == _verdicts(local_records), output[-4000:]
        # The rerun resumes: every task is recorded, nothing is run or written again.
        again = _finish(_bench(cluster, *args))
    assert "0 new task records" in again, again[-4000:]
    assert [r["key"] for r in read_records(out / "results.jsonl")] == [r["key"] for r in records]


@needs_ray
@pytest.mark.slow
def test_generation_on_ray_writes_the_files_a_local_generation_writes(
        cluster: Any, tmp_path: Path) -> None:
    from benchmark.running.generation import generate_suite
    only = ["area_search-easy-2", "target_assignment-easy-3"]
    local = generate_suite(tmp_path / "local", only=only, verify=False)
    output = _finish(_bench(cluster, "generate", "--only", *only, "--no-verify",
                            "--workers", "2", "--out", str(tmp_path / "ray")))
    assert "wrote 2 session files" in output
    for path in local:
        assert (tmp_path / "ray" / path.name).read_bytes() == path.read_bytes()


def test_asking_for_ray_without_it_says_how_to_install_it(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` now raises ImportError
    with pytest.raises(BackendUnavailable, match=r"pip install 'mavswarm\[ray\]'"):
        make_backend("ray", workers=2)
    plan = RunPlan(sessions=(), out_dir=tmp_path / "out", backend="ray")
    with pytest.raises(BackendUnavailable):
        run_benchmark(plan, progress=lambda _: None)
    assert not (tmp_path / "out").exists()  # refused before anything was written


def test_backend_arguments_are_checked() -> None:
    with pytest.raises(ValueError, match="--backend ray"):
        make_backend("local", workers=1, ray_address="127.0.0.2:6379")
    with pytest.raises(ValueError, match="unknown backend"):
        make_backend("dask", workers=1)
    with pytest.raises(ValueError, match="workers"):
        make_backend("local", workers=0)


def test_the_local_backend_imports_no_ray() -> None:
    code = ("import json, sys\n"
            "import benchmark.cli, benchmark.running.orchestrator, benchmark.running.backends\n"
            "import mavswarm.cli\n"
            "from benchmark.running.backends import make_backend\n"
            "make_backend('local', workers=2)\n"
            "print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] == 'ray')))\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                         text=True, check=True, timeout=60)
    assert json.loads(out.stdout.strip().splitlines()[-1]) == []
