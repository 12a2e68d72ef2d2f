"""What the web console's live view costs the server: `mavswarm up --drones N --web` in its
own process, its CPU measured over a window with no page watching, then over a window with K
WebSocket clients receiving the live frames.

    ./dev perf console_live [--drones 250] [--hz 10] [--window 15] [--clients 1] [--rounds 3]

CPU % is the `up` process's CPU time (all threads) / wall time over the window, in % of one
core; the console's cost is the difference. Frames/s and frame size are what the clients got.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import socket
import statistics
import subprocess
import sys
import time

import websockets

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import free_udp_port, machine_line, table

TICK_S = os.sysconf("SC_CLK_TCK")


def _free_tcp_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _cpu_s(pid: int) -> float:
    with open(f"/proc/{pid}/stat") as handle:
        fields = handle.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK_S


async def _watch(url: str, seconds: float, clients: int) -> tuple[int, int]:
    frames = size = 0

    async def one() -> None:
        nonlocal frames, size
        async with websockets.connect(url, max_size=None) as ws:
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                text = await asyncio.wait_for(ws.recv(), 5)
                frames += 1
                size += len(text)

    await asyncio.gather(*(one() for _ in range(clients)))
    return frames, size


def _window(pid: int, seconds: float) -> float:
    c0, w0 = _cpu_s(pid), time.monotonic()
    time.sleep(seconds)
    return 100.0 * (_cpu_s(pid) - c0) / (time.monotonic() - w0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--drones", type=int, default=250)
    parser.add_argument("--hz", type=float, default=10.0)
    parser.add_argument("--window", type=float, default=15.0)
    parser.add_argument("--clients", type=int, default=1)
    parser.add_argument("--rounds", type=int, default=3,
                        help="alternate unwatched and watched windows this many times")
    args = parser.parse_args()
    port, key = _free_tcp_port(), "bench"
    cmd = [sys.executable, "-m", "mavswarm", "up", "--drones", str(args.drones), "--web",
           "--web-port", str(port), "--web-key", key, "--web-hz", str(args.hz), "--no-truth",
           "--api-port", str(free_udp_port()), "--gcs-port", "0",
           "--bind-port", str(free_udp_port())]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        assert proc.stdout is not None
        for line in proc.stdout:
            if "web console:" in line:
                break
        time.sleep(3.0)  # past start-up
        url = f"ws://127.0.0.1:{port}/api/live/swarm/ws?key={key}"
        alones, watcheds, frames, size, wall = [], [], 0, 0, 0.0
        for _ in range(args.rounds):
            alones.append(_window(proc.pid, args.window))
            c0, w0 = _cpu_s(proc.pid), time.monotonic()
            got, nbytes = asyncio.run(_watch(url, args.window, args.clients))
            seconds = time.monotonic() - w0
            watcheds.append(100.0 * (_cpu_s(proc.pid) - c0) / seconds)
            frames, size, wall = frames + got, size + nbytes, wall + seconds
        alone, watched = statistics.median(alones), statistics.median(watcheds)
        page_fps = _page_frames_per_s(f"http://127.0.0.1:{port}/live/swarm?key={key}",
                                      args.window)
    finally:
        proc.terminate()
        proc.wait(10)
    print(machine_line())
    print(f"mavswarm up --drones {args.drones} --web, live frames at {args.hz:g} Hz, "
          f"{args.clients} client(s), {args.window:g} s windows")
    build_ms = _frame_build_ms(args.drones)
    if page_fps is not None:
        print(f"headless Chromium (software WebGL) showing the live view: {page_fps:.1f} "
              "frames/s drawn into its 2D map and 3D view")
    print(table(["no page: up CPU %", "watched: up CPU %", "difference", "frames/s/client",
                 "kB/frame", "frame build ms", "build CPU % at rate"],
                [[f"{alone:.1f}", f"{watched:.1f}", f"{watched - alone:+.1f}",
                  f"{frames / args.clients / wall:.1f}",
                  f"{size / max(1, frames) / 1000:.1f}", f"{build_ms:.2f}",
                  f"{build_ms * args.hz / 10:.2f}"]]))
    print("CPU % columns: medians over the rounds of the `up` process's CPU time / wall time; "
          "frame build: one frame of every drone's state as JSON, timed in this process")


def _page_frames_per_s(url: str, seconds: float) -> float | None:
    """Frames per second the console page itself takes in (None without chromium)."""
    import shutil
    chromium = shutil.which("chromium")
    if chromium is None:
        return None
    from playwright.sync_api import sync_playwright
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium, args=[
            "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"])
        page = browser.new_page(viewport={"width": 1500, "height": 900})
        page.goto(url)
        page.wait_for_function("window.consoleView && window.consoleView.state.frames > 5",
                               timeout=30_000)
        f0, t0 = page.evaluate("window.consoleView.state.frames"), time.monotonic()
        time.sleep(seconds)
        f1 = page.evaluate("window.consoleView.state.frames")
        rate = (f1 - f0) / (time.monotonic() - t0)
        browser.close()
    return rate


def _frame_build_ms(drones: int, repeats: int = 200) -> float:
    from emulator.flight.fleet import Fleet
    from emulator.live_state import live_state
    from emulator.scenario import default_scenario
    fleet = Fleet(default_scenario(drones))
    start = time.perf_counter()
    for _ in range(repeats):
        json.dumps({**live_state(fleet), "act": {}}, separators=(",", ":"))
    return 1000 * (time.perf_counter() - start) / repeats


if __name__ == "__main__":
    main()
