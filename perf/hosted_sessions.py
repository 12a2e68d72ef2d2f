"""Hosted sessions at once: how many lockstep sessions ONE process holds while an external
agent drives each (`bench run --agent external --workers K`, its worker pinned to one core),
with the memory and CPU each session costs.

    ./dev perf hosted_sessions                      # K = 2, 8, 32; 2 tasks each, 2 s think
    ./dev perf hosted_sessions --sessions 2 16 64 --think-s 2 --tasks 2

For each K: K copies of an easy session (3 drones) cut to --tasks tasks, one hosted run (one
worker process on one core, K sessions side by side in its event loop) and K agent threads in
this process, each taking tasks with GET /next and playing a scripted task (every drone up, a
hover, every drone down) over REST, thinking --think-s before every call as a model would.
Prints per K: tasks recorded (the script flies, it does not try to pass), the wall time, the
worker's peak memory and the memory each session added over the first row's K, and its CPU per
session (CPU time over wall). K = 1 runs in the driver process itself, so start at K >= 2.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import httpx
from _common import machine_line, table
from external_agent import script_for

from benchmark.authoring.suite import SESSIONS_DIR

ROOT = Path(__file__).resolve().parents[1]
SESSION = "area_search-easy-1"


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONUNBUFFERED": "1",
            "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}


def _sessions(folder: Path, count: int, tasks: int) -> list[Path]:
    data = json.loads((SESSIONS_DIR / f"{SESSION}.json").read_text())
    paths = []
    for k in range(count):
        path = folder / f"hosted-{k}.json"
        path.write_text(json.dumps({**data, "id": f"hosted-{k}", "tasks": data["tasks"][:tasks]}))
        paths.append(path)
    return paths


def _children(pid: int) -> list[int]:
    try:
        text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    except OSError:
        return []
    return [int(x) for x in text.split()]


def _rss_mb(pid: int) -> float:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return 0.0


def _cpu_s(pid: int) -> float:
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _agent(url: str, think_s: float, done: list[int], stop: threading.Event) -> None:
    with httpx.Client(timeout=None) as http:
        while not stop.is_set():
            answer = http.get(f"{url}/next")
            if answer.status_code in (204, 409):  # the run ended; the tasks left are out
                return
            if answer.status_code == 503:
                continue
            answer.raise_for_status()
            task = answer.json()
            for name, arguments in script_for(task["drones"]):
                time.sleep(think_s)
                http.post(f"{task['tools_url']}/{name}", json=arguments,
                          headers={"X-API-Key": task["key"]})
            done.append(1)


def one(count: int, tasks: int, think_s: float, folder: Path) -> dict[str, Any]:
    paths = _sessions(folder, count, tasks)
    out = folder / f"run-{count}"
    host = subprocess.Popen(
        ["taskset", "-c", "0", sys.executable, "-m", "mavswarm", "bench", "run", "--agent",
         "external", "--port", "0", "--workers", str(count), "--out", str(out),
         "--sessions", *map(str, paths)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=ROOT, env=_env())
    assert host.stdout is not None
    url = None
    for line in host.stdout:
        found = re.search(r"endpoint (http://\S+)", line)
        if found:
            url = found.group(1)
            break
    if url is None:
        raise RuntimeError("the hosted run printed no endpoint")
    threading.Thread(target=lambda: [None for _ in host.stdout or ()], daemon=True).start()
    done: list[int] = []
    stop = threading.Event()
    start = time.perf_counter()
    agents = [threading.Thread(target=_agent, args=(url, think_s, done, stop), daemon=True)
              for _ in range(count)]
    for a in agents:
        a.start()
    peak_mb, worker, cpu = 0.0, host.pid, 0.0
    while any(a.is_alive() for a in agents):
        kids = _children(host.pid)  # the worker, and multiprocessing's resource tracker
        worker = max(kids, key=_rss_mb) if count > 1 and kids else host.pid
        peak_mb = max(peak_mb, _rss_mb(worker))
        cpu = max(cpu, _cpu_s(worker))
        time.sleep(0.5)
    wall = time.perf_counter() - start
    host.wait(timeout=120)
    records = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    return {"sessions": count, "tasks": len(records), "agent_tasks": len(done), "wall_s": wall,
            "peak_mb": peak_mb, "cpu_s": cpu, "load": os.getloadavg()[0]}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sessions", type=int, nargs="+", default=[2, 8, 32])
    p.add_argument("--tasks", type=int, default=2, help="tasks per session")
    p.add_argument("--think-s", type=float, default=2.0)
    args = p.parse_args()
    print(machine_line(), flush=True)
    rows, first = [], None
    with tempfile.TemporaryDirectory() as tmp:
        for count in args.sessions:
            r = one(count, args.tasks, args.think_s, Path(tmp))
            first = first or r
            extra = ((r["peak_mb"] - first["peak_mb"]) / (count - first["sessions"])
                     if count > first["sessions"] else float("nan"))
            rows.append([count, f"{r['tasks']}/{count * args.tasks}",
                         f"{r['wall_s']:.0f}", f"{r['peak_mb']:.0f}", f"{extra:.1f}",
                         f"{100 * r['cpu_s'] / r['wall_s']:.0f}",
                         f"{100 * r['cpu_s'] / r['wall_s'] / count:.1f}", f"{r['load']:.1f}"])
            print("  ", rows[-1], flush=True)
    print(f"\none worker process on one core hosting K sessions, an external agent per session "
          f"(REST, {args.think_s:g} s think before each call)")
    print(table(["K", "tasks", "wall s", "worker RSS MB", "MB per added session",
                 "worker CPU %", "CPU % per session", "load avg"], rows))


if __name__ == "__main__":
    main()
