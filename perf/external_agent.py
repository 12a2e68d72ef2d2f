"""What hosting costs an agent outside the process (`bench run --agent external`):

1. the time a tool call takes as the agent sees it, in-process (the tool registry on the
   episode's tools) against the same call over REST (httpx, keep-alive) and over MCP (the
   official SDK's client) to a hosted run in another process; target: p50 <= 5 ms added;
2. the wall time of a whole hosted run played by a scripted external agent (a client process
   over REST) against the same agent in-process, each run as a process of its own; target:
   within 1.5x.

    ./dev perf external_agent [--calls 300] [--repeats 3] [--suite smoke | --sessions FILE ...]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import httpx
from _common import machine_line, pct, table

from agent_contract import AgentTask, AgentTools
from benchmark.authoring.session_file import load_session
from benchmark.authoring.suite import suite_paths
from benchmark.running.episode import run_session
from llm_tools.registry import default_registry
from tests.bench_fixtures import small_session, write_json

ROOT = Path(__file__).resolve().parents[1]
PROBE = ("drone_state", {"drone_id": "d1"})


def _mavswarm(*args: str) -> list[str]:
    return [sys.executable, "-m", "mavswarm", *args]


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONUNBUFFERED": "1",
            "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}


def _host(sessions: list[Path], out: Path) -> tuple[subprocess.Popen[str], str]:
    proc = subprocess.Popen(_mavswarm("bench", "run", "--agent", "external", "--port", "0",
                                      "--out", str(out), "--sessions", *map(str, sessions)),
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            cwd=ROOT, env=_env())
    assert proc.stdout is not None
    for line in proc.stdout:
        found = re.search(r"endpoint (http://\S+)", line)
        if found:
            return proc, found.group(1)
    raise RuntimeError("the hosted run printed no endpoint")


# ------------------------------------------------------------------ 1: per call
class Probe:
    """An in-process agent timing `calls` registry calls of the probe tool."""

    name = "probe"

    def __init__(self, calls: int) -> None:
        self.calls, self.samples = calls, list[float]()
        self.registry = default_registry()

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        for _ in range(self.calls):
            t = time.perf_counter()
            await self.registry.call(tools, *PROBE)
            self.samples.append(time.perf_counter() - t)
        tools.finish()


def _rest_samples(task: dict[str, Any], calls: int) -> list[float]:
    samples = []
    with httpx.Client(headers={"X-API-Key": task["key"]}, timeout=60.0) as http:
        for _ in range(calls):
            t = time.perf_counter()
            http.post(f"{task['tools_url']}/{PROBE[0]}", json=PROBE[1]).raise_for_status()
            samples.append(time.perf_counter() - t)
        http.post(f"{task['tools_url']}/finish", json={}).raise_for_status()
    return samples


async def _mcp_samples(task: dict[str, Any], calls: int) -> list[float]:
    import httpx2
    from mcp import Client
    from mcp.client.streamable_http import streamable_http_client
    samples = []
    http = httpx2.AsyncClient(headers={"X-API-Key": task["key"]}, timeout=60.0)
    async with http, Client(streamable_http_client(task["mcp_url"], http_client=http)) as mcp:
        for _ in range(calls):
            t = time.perf_counter()
            result = await mcp.call_tool(*PROBE)
            samples.append(time.perf_counter() - t)
            assert not result.is_error, result
        await mcp.call_tool("finish", {})
    return samples


def per_call(calls: int, folder: Path) -> None:
    data = small_session(["takeoff_hold", "takeoff_hold"])
    for task in data["tasks"]:
        task["budget"]["tool_calls"] = calls + 10
    session = write_json(folder / "probe.json", data)
    probe = Probe(calls)
    asyncio.run(run_session(load_session(session), probe, emit=lambda record: None))
    proc, url = _host([session], folder / "probe-run")
    try:
        rest = _rest_samples(httpx.get(f"{url}/next", timeout=60).json(), calls)
        mcp = asyncio.run(_mcp_samples(httpx.get(f"{url}/next", timeout=60).json(), calls))
        assert httpx.get(f"{url}/next", timeout=60).status_code == 204
        proc.wait(timeout=60)
    finally:
        proc.kill()
    base = pct(probe.samples, 50)
    rows = []
    for name, samples in (("in-process", probe.samples), ("REST", rest), ("MCP", mcp)):
        p50 = pct(samples, 50)
        rows.append([name, f"{p50 * 1e3:.3f}", f"{pct(samples, 95) * 1e3:.3f}",
                     "-" if name == "in-process" else f"{(p50 - base) * 1e3:+.3f}"])
    print(f"\n1. one {PROBE[0]} call as the agent sees it ({calls} calls each; target: p50 "
          "added <= 5 ms)")
    print(table(["surface", "p50 ms", "p95 ms", "p50 added ms"], rows))


# ------------------------------------------------------------------ 2: a whole run
def script_for(drones: list[str]) -> list[list[Any]]:
    """The scripted agent's calls for any task: every drone up, a hover, every drone down."""
    calls: list[list[Any]] = [["list_drones", {}]]
    calls += [["take_off", {"drone_id": d, "altitude_m": 10.0}] for d in drones]
    calls.append(["hover", {"drone_id": drones[0], "duration_s": 3.0}])
    calls += [["land", {"drone_id": d}] for d in drones]
    return [*calls, ["finish", {}]]


class Scripted:
    name = "scripted"

    def __init__(self) -> None:
        self.registry = default_registry()

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        for name, arguments in script_for(tools.drone_ids):
            await self.registry.call(tools, name, arguments)


def in_process_run(out: str, paths: list[str]) -> None:
    """(In a process of its own.) The scripted agent over the sessions in-process, as `bench
    run` runs an agent: the orchestrator writes the results, then the reports."""
    here = str(Path(__file__).resolve().parent)  # its scripts would shadow packages
    sys.path[:] = [p for p in sys.path if p not in (here, "")]
    import mavswarm.cli  # noqa: F401  (what `mavswarm bench run` loads before it runs)
    from benchmark.reporting.report import write_report
    from benchmark.running import orchestrator
    from benchmark.running.results import read_records
    orchestrator.make_agent = lambda *args, **kwargs: Scripted()  # the agent under test
    plan = orchestrator.RunPlan(sessions=tuple(map(Path, paths)), agent="noop",
                                out_dir=Path(out))
    orchestrator.run_benchmark(plan, progress=lambda line: None)
    write_report(read_records(plan.results_path), plan.out_dir)


def _external_client(url: str) -> int:
    tasks = 0
    with httpx.Client(timeout=None) as http:
        while (answer := http.get(f"{url}/next")).status_code != 204:
            if answer.status_code == 503:
                continue
            answer.raise_for_status()
            task, tasks = answer.json(), tasks + 1
            for name, arguments in script_for(task["drones"]):
                http.post(f"{task['tools_url']}/{name}", json=arguments,
                          headers={"X-API-Key": task["key"]})
    return tasks


def _one_pair(paths: list[Path], folder: Path, k: int) -> tuple[float, float, int]:
    t = time.perf_counter()
    subprocess.run([sys.executable, __file__, "--in-process-run", str(folder / f"local-{k}"),
                    *map(str, paths)], check=True, cwd=ROOT, env=_env())
    local_s = time.perf_counter() - t
    t = time.perf_counter()
    proc, url = _host(paths, folder / f"hosted-{k}")
    try:
        tasks = _external_client(url)
        proc.wait(timeout=120)
    finally:
        proc.kill()
    return local_s, time.perf_counter() - t, tasks


def whole_run(paths: list[Path], limit: int | None, folder: Path, repeats: int) -> None:
    if limit is not None:  # the hosted run takes session files: cut them to the limit
        cut = []
        for path in paths:
            data = json.loads(path.read_text())
            cut.append(write_json(folder / path.name, {**data, "tasks": data["tasks"][:limit]}))
        paths = cut
    pairs = [_one_pair(paths, folder, k) for k in range(repeats)]
    rows = [[str(k + 1), f"{local_s:.1f}", f"{hosted_s:.1f}", f"{hosted_s / local_s:.2f}"]
            for k, (local_s, hosted_s, _) in enumerate(pairs)]
    ratios = sorted(hosted_s / local_s for local_s, hosted_s, _ in pairs)
    print(f"\n2. a whole run, {len(paths)} session(s), {pairs[0][2]} tasks, the same scripted "
          "agent in-process and as a REST client process, each run a `bench run`-like "
          "process of its own (target: hosted within 1.5x)")
    print(table(["pair", "in-process s", "hosted s", "ratio"], rows))
    print(f"median ratio {ratios[len(ratios) // 2]:.2f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--calls", type=int, default=300)
    parser.add_argument("--repeats", type=int, default=3, help="whole-run pairs")
    parser.add_argument("--suite", default="smoke")
    parser.add_argument("--sessions", type=Path, nargs="+")
    parser.add_argument("--in-process-run", nargs="+", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.in_process_run:
        in_process_run(args.in_process_run[0], args.in_process_run[1:])
        return
    print(machine_line())
    paths, limit = (list(args.sessions), None) if args.sessions else suite_paths(args.suite)
    with tempfile.TemporaryDirectory() as tmp:
        per_call(args.calls, Path(tmp))
        whole_run(list(paths), limit, Path(tmp), args.repeats)


if __name__ == "__main__":
    main()
