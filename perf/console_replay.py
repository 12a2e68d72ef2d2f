"""Replay data of extreme-level tasks: its size per task, and the time to open a task's replay
in the run inspector: the API answer, and in headless Chromium (software WebGL) the time from
navigation until the map and timeline are drawn and until the 3D view is, for the first open
of a fresh browser page and the median of --opens.

    ./dev perf console_replay [--session area_search-extreme-1] [--tasks 5 | --only t01,t02]
                               [--opens 5]

The oracle flies the first --tasks tasks of the session with `mavswarm bench run`, which
stores each task's replay beside results.jsonl; `mavswarm replay` then serves the folder.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import httpx

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import machine_line, table

ROOT = Path(__file__).resolve().parents[1]


def _free_tcp_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _browser_open_s(url: str, opens: int) -> list[tuple[float, float]]:
    """Per open: seconds from navigation start until the map and timeline are drawn, and
    until the 3D view is (the page marks both)."""
    chromium = shutil.which("chromium")
    if chromium is None:
        return []
    from playwright.sync_api import sync_playwright
    times = []
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium, args=[
            "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"])
        for _ in range(opens):
            page = browser.new_page(viewport={"width": 1500, "height": 900})
            page.goto(url)
            page.wait_for_function("performance.getEntriesByName('replay-3d').length > 0",
                                   timeout=30_000)
            marks = page.evaluate("['replay-2d', 'replay-3d'].map("
                                  "n => performance.getEntriesByName(n)[0].startTime)")
            times.append((marks[0] / 1000, marks[1] / 1000))
            page.close()
        browser.close()
    return times


def _opens(times: list[float]) -> str:
    if not times:
        return "no chromium"
    return f"{times[0]:.2f}, {statistics.median(times):.2f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--session", default="area_search-extreme-1")
    parser.add_argument("--tasks", type=int, default=5)
    parser.add_argument("--opens", type=int, default=5)
    parser.add_argument("--only", default="", help="comma-separated task ids (else the first "
                        "--tasks tasks)")
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="console-replay-"))
    data = json.loads((ROOT / "benchmark" / "sessions" / f"{args.session}.json").read_text())
    wanted = [t for t in args.only.split(",") if t]
    data["tasks"] = ([t for t in data["tasks"] if t["id"] in wanted] if wanted
                     else data["tasks"][: args.tasks])
    session = work / "session.json"
    session.write_text(json.dumps(data))
    mavswarm = [sys.executable, "-m", "mavswarm"]
    started = time.perf_counter()
    subprocess.run([*mavswarm, "bench", "run", "--agent", "oracle", "--sessions", str(session),
                    "--out", str(work / "run")], check=True, capture_output=True)
    run_s = time.perf_counter() - started
    records = [json.loads(line) for line in (work / "run" / "results.jsonl").read_text()
               .splitlines()]
    folder = work / "run" / "replay" / args.session
    port = _free_tcp_port()
    server = subprocess.Popen([*mavswarm, "replay", str(work / "run"), "--port", str(port)],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    rows = []
    try:
        assert server.stdout is not None
        server.stdout.readline()
        base = f"http://127.0.0.1:{port}"
        for record in records:
            path = folder / f"{record['task']}.oracle.0.json.gz"
            api = []
            for _ in range(args.opens):
                t0 = time.perf_counter()
                httpx.get(f"{base}/api/task/{args.session}/{record['task']}?trial=0").raise_for_status()
                api.append(time.perf_counter() - t0)
            page = _browser_open_s(f"{base}/inspect/{args.session}/{record['task']}?trial=0",
                                   args.opens)
            rows.append([record["task"], record["template"], f"{record['sim_time_s']:.0f}",
                         record["tool_calls"], f"{path.stat().st_size / 1000:.1f}",
                         f"{1000 * statistics.median(api):.0f}",
                         _opens([p[0] for p in page]), _opens([p[1] for p in page])])
    finally:
        server.terminate()
        server.wait(10)
    print(machine_line())
    print(f"{args.session}: {len(data['drones'])} drones, {len(data['obstacles'])} obstacles; "
          f"oracle run of {len(records)} tasks in {run_s:.1f} s; world file "
          f"{(folder / 'world.json.gz').stat().st_size / 1000:.1f} kB")
    print(table(["task", "template", "sim s", "calls", "replay kB", "API ms (p50)",
                 "2D+timeline s (first, p50)", "3D s (first, p50)"], rows))
    shutil.rmtree(work)


if __name__ == "__main__":
    main()
