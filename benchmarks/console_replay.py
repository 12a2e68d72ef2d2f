"""Replay data of extreme-level tasks: its size per task, and the time to open a task's replay
in the run inspector (the API answer, and the page in headless Chromium until it has drawn).

    ./dev bench console_replay [--session area_search-extreme-1] [--tasks 5] [--opens 5]

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


def _browser_open_s(url: str, opens: int) -> list[float]:
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
            start = time.perf_counter()
            page.goto(url)
            page.wait_for_selector("body[data-ready='1']", timeout=30_000)
            page.evaluate("new Promise(r => requestAnimationFrame(() => r(1)))")
            times.append(time.perf_counter() - start)
            page.close()
        browser.close()
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--session", default="area_search-extreme-1")
    parser.add_argument("--tasks", type=int, default=5)
    parser.add_argument("--opens", type=int, default=5)
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="console-replay-"))
    data = json.loads((ROOT / "benchmark" / "sessions" / f"{args.session}.json").read_text())
    data["tasks"] = data["tasks"][: args.tasks]
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
                         f"{statistics.median(page):.2f}" if page else "no chromium"])
    finally:
        server.terminate()
        server.wait(10)
    print(machine_line())
    print(f"{args.session}: {len(data['drones'])} drones, {len(data['obstacles'])} obstacles; "
          f"oracle run of {len(records)} tasks in {run_s:.1f} s; world file "
          f"{(folder / 'world.json.gz').stat().st_size / 1000:.1f} kB")
    print(table(["task", "template", "sim s", "calls", "replay kB", "API ms (p50)",
                 "page open s (p50)"], rows))
    shutil.rmtree(work)


if __name__ == "__main__":
    main()
