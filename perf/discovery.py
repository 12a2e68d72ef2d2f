"""MAVSDK discovery time for N vehicles on one shared socket.

    ./dev perf discovery [--sizes 10,100,250] [--repeat 5] [--poll-ms 10]

For each N one emulator process (`Swarm(default_scenario(N))`, speed 1, shared socket on
127.0.0.1, default streams: HEARTBEAT 1 Hz with phases staggered over the second) runs for
all repetitions. Each repetition creates a fresh `Mavsdk` (GROUND_STATION) in this process,
with the loop's default executor set to ThreadPoolExecutor(N + 16), and times from
`add_any_connection("udpin://127.0.0.1:PORT")` until `get_systems()` holds N systems that
are all `is_connected()` and `has_autopilot()` (polled every --poll-ms). The Mavsdk is
destroyed between repetitions; repetitions start at random heartbeat phases.
"""

from __future__ import annotations

import argparse
import asyncio
import os
import random
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import Emulator, free_udp_port, machine_line, table
from _mavsdk import new_mavsdk, set_executor, wait_for_systems, warnings_line


async def discover(port: int, n: int, poll_s: float, timeout_s: float) -> dict:
    set_executor(n)
    mavsdk = new_mavsdk()
    try:
        t0 = time.monotonic()
        await mavsdk.add_any_connection(f"udpin://127.0.0.1:{port}")
        systems, t_first, t_all = await wait_for_systems(mavsdk, n, t0, timeout_s, poll_s)
    finally:
        t = time.monotonic()
        mavsdk.destroy()
        t_destroy = time.monotonic() - t
    return {"first": t_first, "all": t_all, "found": len(systems), "destroy": t_destroy}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", default="10,100,250")
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--poll-ms", type=float, default=10.0)
    p.add_argument("--timeout", type=float, default=20.0, help="s per discovery attempt")
    args = p.parse_args()
    sizes = [int(s) for s in args.sizes.split(",")]
    print(f"discovery: sizes {sizes}, {args.repeat} repetitions each, poll {args.poll_ms:g} ms, "
          f"executor N+16 threads, MAVSDK udpin on 127.0.0.1, emulator speed 1, shared socket")
    print(machine_line(), flush=True)
    rows = []
    for n in sizes:
        port = free_udp_port()
        with Emulator(n, port) as emu:
            time.sleep(1.0)
            firsts, alls, missing = [], [], 0
            for _ in range(args.repeat):
                time.sleep(random.uniform(0.2, 1.2))  # random heartbeat phase
                r = asyncio.run(discover(port, n, args.poll_ms / 1000.0, args.timeout))
                firsts.append(r["first"])
                if r["found"] < n:
                    missing += 1
                else:
                    alls.append(r["all"])
                print(f"  N={n}: first {r['first']:.3f} s, all {r['all']:.3f} s "
                      f"({r['found']} found), Mavsdk.destroy() {r['destroy']:.2f} s", flush=True)
            stats = emu.snap()
        rows.append([n, len(alls), f"{statistics.median(firsts):.3f}",
                     f"{statistics.median(alls):.3f}" if alls else "-",
                     f"{min(alls):.3f}" if alls else "-", f"{max(alls):.3f}" if alls else "-",
                     missing, stats["frames_bad"]])
    print("\n" + table(["N", "runs ok", "first system median s", "all N median s", "min s",
                        "max s", "timeouts", "bad frames"], rows))
    print("first system: add_any_connection to the first entry in get_systems(); all N: to all "
          "N is_connected and has_autopilot; about one heartbeat period, as the vehicles' 1 Hz "
          "heartbeat phases are spread over the second.")
    print(warnings_line())


if __name__ == "__main__":
    main()
