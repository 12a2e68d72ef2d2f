"""How many vehicles hold real time with full telemetry, alone and with a MAVSDK client.

    ./dev perf scale [--sizes 10,50,100,250] [--window 15] [--alone-window 10]
                      [--networks 4] [--clients 4,1] [--api asyncio|callback]
                      [--streams default|issue] [--largest-step 1000] [--largest-max 20000]
                      [--skip alone,largest,client,multi] [--profile FILE] [--quick]
                      [--cost 1000,10000 [--cost-seconds 10]]

    --quick   = --sizes 250,1000 --skip client,multi --alone-window 5 --warmup 2
                --largest-step 2500 (a few minutes: the targets' figures and the largest N
                alone, to 2,500 vehicles)

Each emulator is `Swarm(default_scenario(N))` in its own process at speed 1 (real-time
pacing, 50 Hz physics; above 250 vehicles, the swarm's MAVLink networks of 250, a socket
each, as system ids stop at 255), shared-socket topology on 127.0.0.1, default telemetry streams
(HEARTBEAT, SYS_STATUS, EXTENDED_SYS_STATE, GPS_RAW_INT, MISSION_CURRENT, camera HEARTBEAT
1 Hz; GLOBAL_POSITION_INT, LOCAL_POSITION_NED, ATTITUDE 10 Hz; VFR_HUD 2 Hz; BATTERY_STATUS,
HOME_POSITION 0.5 Hz), sending to one destination port and no GCS port. Vehicles sit on the
ground (telemetry cost does not depend on flying).

  alone   the emulator sends into a bound socket that a thread of this process drains
  client  one MAVSDK process (udpin) discovers all N and subscribes to position on each
  largest the emulator alone at N = max(sizes) + step, + 2 steps, ... (--largest-step, up to
          --largest-max) until one misses RTF >= 0.995 or 99 % of its telemetry: the
          largest N one process holds (measured, not extrapolated)
  multi   `--networks` emulator processes of 250 (separate ports), alone, then with K
          clients for each K in --clients (client j on network j)

--cost N,...: instead of the above, the CPU one process needs per second of real time for N
vehicles, measured flat out so a busy machine cannot starve it: the swarm of N (MAVLink
networks of 250, real sockets, into a drained sink) with its scheduler idle, driven turn by turn
as the real-time scheduler drives it (a 20 ms turn: one 50 Hz physics step, the telemetry due,
the link ticks every 50 ms, the datagrams sent) on a simulated wall clock, for --cost-seconds.
"need %" = this thread's CPU s / simulated s (the event loop's sleeps and wake-ups are left
out); the real-time run above is what shows it holding.

--streams issue keeps only issue 16's "full telemetry" (HEARTBEAT, SYS_STATUS,
EXTENDED_SYS_STATE 1 Hz; GLOBAL_POSITION_INT, ATTITUDE, LOCAL_POSITION_NED 10 Hz: 33 messages/s
per vehicle); the default streams are a superset of it (39/s).

CPU % is the process's CPU time (all threads) / wall over the window, in % of one core.
RTF = simulated seconds / wall seconds over the window (swarm.stats()); "slip" is the
simulated time the clock gave up because the process could not keep up.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import os
import pstats
import re
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import Emulator, UdpSink, free_udp_port, host_busy_s, machine_line, rates, table
from _mavsdk import Client

from emulator.mavlink.streams import DEFAULT_STREAMS
from emulator.networks import MAX_FLEET_VEHICLES, network_count

RTF_OK = 0.995  # the window edges are quantised to one 20 ms physics step
TELE_OK = 99.0  # % of the nominal telemetry sent
ISSUE_STREAMS = ("HEARTBEAT", "SYS_STATUS", "EXTENDED_SYS_STATE", "GLOBAL_POSITION_INT",
                 "ATTITUDE", "LOCAL_POSITION_NED")
TARGETS = {250: 15.0, 1000: 50.0}  # issue 16: emulator alone, % of one core
STREAM_HZ: dict[str, float] = {}  # --streams issue: the streams switched off
NOMINAL = sum(s.default_hz for s in DEFAULT_STREAMS)  # messages/s per vehicle (39; issue: 33)


def _emu_cols(r: dict, n: int) -> list[str]:
    return [f"{r['cpu_pct']:.1f}", f"{r['sim']:.3f}", f"{r['slipped']:.2f}",
            f"{r['out']:.0f}", f"{100 * r['out'] / n / NOMINAL:.0f}"]


EMU_HEAD = ["emu CPU %", "RTF", "slip s/s", "msgs/s out", "tele %"]
CLIENT_HEAD = ["msgs/s in", "client CPU %", "pos cb/s/veh mean", "min", "MAVSDK warn"]
WARN_LAST: list[str] = []  # the MAVSDK warning texts seen, for the footer


def _warn(c: dict) -> str:
    text = re.sub(r"\d+", "N", c["warn_last"])
    if c["warn"] and text not in WARN_LAST:
        WARN_LAST.append(text)
    return str(c["warn"])


def measure(emus: list[Emulator], clients: list[Client], warmup_s: float, window_s: float,
            sinks: tuple[UdpSink, ...] = ()):
    """Rates of each emulator and client over the window; sets measure.host (% of one core
    the whole machine was busy) and measure.own (this process: the sinks' drain thread)."""
    time.sleep(warmup_s)
    a = [e.snap() for e in emus] + [c.snap() for c in clients]
    h0, w0, p0 = host_busy_s(), time.monotonic(), time.process_time()
    for s in sinks:
        s.mark = s.count
    time.sleep(window_s)
    b = [e.snap() for e in emus] + [c.snap() for c in clients]
    wall = time.monotonic() - w0
    measure.host = 100 * (host_busy_s() - h0) / wall
    measure.own = 100 * (time.process_time() - p0) / wall
    for s in sinks:
        s.mark = s.count - s.mark
    rs = [rates(x, y) for x, y in zip(a, b, strict=True)]
    return rs[: len(emus)], rs[len(emus):]


def alone_row(n: int, args) -> list:
    sink = UdpSink(ports=network_count(n))  # network j of the swarm sends to port + j
    try:
        with Emulator(n, sink.port, telemetry_hz=STREAM_HZ,
                      timeout_s=60.0 + n / 20.0) as emu:
            (r,), _ = measure([emu], [], args.warmup, args.alone_window, (sink,))
            drained = sink.mark / r["wall"]
    finally:
        sink.close()
    return [n, *_emu_cols(r, n), f"{drained:.0f}", f"{measure.own:.1f}", f"{measure.host:.0f}",
            f"{os.getloadavg()[0]:.1f}"]


def holds(row: list) -> bool:
    """RTF >= 0.995 and >= 99 % of the telemetry (an alone row)."""
    return float(row[2]) >= RTF_OK and float(row[5]) >= TELE_OK


def run_alone(sizes: list[int], args) -> list[list]:
    rows = []
    for n in sizes:
        rows.append(alone_row(n, args))
        print("  alone", rows[-1], flush=True)
    return rows


def run_largest(start: int, args) -> tuple[list[list], int | None]:
    """Alone at start + step, + 2 steps, ... until a size misses; the last size that held."""
    rows: list[list] = []
    held = None
    n = start + args.largest_step
    while n <= args.largest_max:
        rows.append(alone_row(n, args))
        print("  largest", rows[-1], flush=True)
        if not holds(rows[-1]):
            break
        held = n
        n += args.largest_step
    return rows, held


def run_with_client(sizes: list[int], args) -> list[list[str]]:
    rows = []
    for n in sizes:
        port = free_udp_port()
        with Client(port, n, api=args.api) as client, \
                Emulator(n, port, telemetry_hz=STREAM_HZ) as emu:
            info = client.ready(60)
            (r,), (c,) = measure([emu], [client], args.warmup, args.window)
        rows.append([n, info["found"], f"{info['discovery_s']:.2f}", *_emu_cols(r, n),
                     f"{r['in']:.0f}", f"{c['cpu_pct']:.1f}", f"{c['cb_mean']:.2f}",
                     f"{c['cb_min']:.2f}", _warn(c), f"{measure.host:.0f}"])
        print("  client", rows[-1], flush=True)
    return rows


def run_multi(networks: int, k_clients: int, args) -> tuple[list[list[str]], str]:
    """`networks` emulators of 250; the first k_clients get a MAVSDK client each."""
    n = 250
    with contextlib.ExitStack() as stack:
        ports = [free_udp_port() for _ in range(networks)]
        clients = [stack.enter_context(Client(ports[j], n, api=args.api))
                   for j in range(k_clients)]
        sinks = [UdpSink() for _ in range(networks - k_clients)]
        stack.callback(lambda: [s.close() for s in sinks])
        dests = ports[:k_clients] + [s.port for s in sinks]
        emus = [stack.enter_context(Emulator(n, dests[j], telemetry_hz=STREAM_HZ))
                for j in range(networks)]
        infos = [c.ready(90) for c in clients]
        rs, cs = measure(emus, clients, args.warmup, args.window, tuple(sinks))
    rows = []
    for j, r in enumerate(rs):
        if j < k_clients:
            c, info = cs[j], infos[j]
            tail = [f"{info['found']}", f"{r['in']:.0f}", f"{c['cpu_pct']:.1f}",
                    f"{c['cb_mean']:.2f}", f"{c['cb_min']:.2f}", _warn(c)]
        else:
            tail = ["-"] * 6
        rows.append([f"net {j}", n, *_emu_cols(r, n), *tail])
    tot_cpu = sum(r["cpu_pct"] for r in rs) + sum(c["cpu_pct"] for c in cs)
    rows.append(["total", n * networks, f"{sum(r['cpu_pct'] for r in rs):.1f}",
                 f"min {min(r['sim'] for r in rs):.3f}", f"{sum(r['slipped'] for r in rs):.2f}",
                 f"{sum(r['out'] for r in rs):.0f}",
                 f"{100 * sum(r['out'] for r in rs) / (n * networks) / NOMINAL:.0f}", "", "",
                 f"{sum(c['cpu_pct'] for c in cs):.1f}", "", "", ""])
    summary = (f"emulators + clients {tot_cpu:.0f}% of one core, sink thread {measure.own:.0f}%, "
               f"whole machine busy {measure.host:.0f}% of one core ({os.cpu_count()} cores)")
    print(f"  {networks} x 250 with {k_clients} client(s): {summary}", flush=True)
    return rows, summary


def profile(n: int, path: str, args) -> None:
    port = free_udp_port()
    with Client(port, n, api=args.api) as client, Emulator(n, port, profile_to=path) as emu:
        client.ready(60)
        emu.ask("profile_on")
        measure([emu], [client], args.warmup, args.window)
        emu.ask("profile_off")
    st = pstats.Stats(path)
    total = st.total_tt
    print(f"\ncProfile of the N={n} emulator with a client ({total:.1f} s profiled: warm-up and "
          f"window, incl. idle epoll), top 20 by own time:")
    st.sort_stats("tottime").print_stats(20)


async def _drive(n: int, seconds: float, sink_port: int) -> dict[str, float]:
    from emulator.clock import ClockConfig
    from emulator.scenario import default_scenario
    from emulator.swarm import PortPlan, Swarm

    swarm = Swarm(default_scenario(n), clock=ClockConfig(stepped=True),
                  ports=PortPlan(bind_host="127.0.0.1", bind_port=0, api_host="127.0.0.1",
                                 api_port=sink_port, gcs_port=0),
                  telemetry_hz=STREAM_HZ or None)
    async with swarm:
        # the swarm's own scheduler stays idle: nothing flies, and its telemetry is due on a
        # clock a day ahead, the one this loop drives
        now = time.monotonic() + 86_400.0
        swarm.streams.next_due_s += now - swarm.streams.next_wakeup_s()
        fleet, turn_s, next_link = swarm.fleet, 0.02, now
        turns = round(seconds / turn_s)
        out0 = swarm.stats().frames_out
        cpu0 = time.thread_time()
        for _ in range(turns):
            now += turn_s
            fleet.step()
            swarm.faults.fire_due()
            if now >= next_link:
                next_link = now + 0.05
                swarm.tick_links(now)
            swarm.send_due_telemetry(now)
            await asyncio.sleep(0)  # the transports send what was queued
        cpu = time.thread_time() - cpu0
        out = swarm.stats().frames_out - out0
        sim = turns * turn_s
    return {"need": 100 * cpu / sim, "us": 1e6 * cpu / sim / n, "tele": 100 * out / sim / n /
            NOMINAL}


def run_cost(sizes: list[int], seconds: float) -> str:
    rows = []
    for n in sizes:
        sink = UdpSink(ports=network_count(n))
        try:
            r = asyncio.run(_drive(n, seconds, sink.port))
        finally:
            sink.close()
        rows.append([n, network_count(n), f"{r['need']:.1f}", f"{r['us']:.1f}",
                     f"{r['tele']:.0f}", f"{os.getloadavg()[0]:.1f}"])
        print("  cost", rows[-1], flush=True)
    return ("\nCPU one process needs for real time, measured flat out (--cost):\n"
            + table(["N", "networks", "need % of a core", "us CPU / vehicle / s", "tele %",
                     "load avg"], rows))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", default="10,50,100,250")
    p.add_argument("--window", type=float, default=15.0, help="s measured, with clients")
    p.add_argument("--alone-window", type=float, default=10.0, help="s measured, alone")
    p.add_argument("--warmup", type=float, default=3.0, help="s after start/discovery")
    p.add_argument("--networks", type=int, default=4)
    p.add_argument("--clients", default="4,1", help="client counts for the multi runs")
    p.add_argument("--api", choices=("asyncio", "callback"), default="asyncio")
    p.add_argument("--skip", default="", help="comma list of: alone, client, multi")
    p.add_argument("--profile", metavar="FILE", help="then cProfile N=max(sizes) with client")
    p.add_argument("--streams", choices=("default", "issue"), default="default",
                   help="'issue': only issue 16's six streams (see above)")
    p.add_argument("--largest-step", type=int, default=1000)
    p.add_argument("--largest-max", type=int, default=MAX_FLEET_VEHICLES)
    p.add_argument("--cost", metavar="SIZES", help="only the CPU needed, flat out (above)")
    p.add_argument("--cost-seconds", type=float, default=10.0)
    p.add_argument("--quick", action="store_true",
                   help="--sizes 250,1000 --skip client,multi --alone-window 5 --warmup 2 "
                        "--largest-step 2500")
    args = p.parse_args()
    if args.quick:
        args.sizes, args.skip = "250,1000", ",".join({"client", "multi", *args.skip.split(",")})
        args.alone_window, args.warmup, args.largest_step = 5.0, 2.0, 2500
    global NOMINAL
    if args.streams == "issue":
        STREAM_HZ.update({s.name: 0.0 for s in DEFAULT_STREAMS if s.name not in ISSUE_STREAMS})
        NOMINAL = sum(s.default_hz for s in DEFAULT_STREAMS if s.name in ISSUE_STREAMS)
    sizes = [int(s) for s in args.sizes.split(",")]
    skip = set(filter(None, args.skip.split(",")))
    print(f"scale: sizes {sizes}, window {args.window:g} s with client / "
          f"{args.alone_window:g} s alone after {args.warmup:g} s warm-up, speed 1 real time, "
          f"physics 50 Hz, {args.streams} streams ({NOMINAL:g} messages/s per vehicle), "
          f"client api {args.api}, 127.0.0.1")
    print(machine_line(), flush=True)
    if args.cost:
        print(run_cost([int(s) for s in args.cost.split(",")], args.cost_seconds))
        return
    out = []
    if "alone" not in skip:
        rows = run_alone(sizes, args)
        ok = [int(r[0]) for r in rows if holds(r)]
        largest = max(ok) if ok else None
        note = ""
        if "largest" not in skip and largest == max(sizes):
            more, held = run_largest(largest, args)
            rows += more
            if held is not None:
                largest = held
            elif not more:
                note = f" (--largest-max {args.largest_max} reached)"
        out.append("\nEmulator alone, one process (sending into a drained sink):\n" + table(
            ["N", *EMU_HEAD, "sink recv/s", "sink CPU %", "host busy %", "load avg"], rows)
            + f"\nlargest N per process with RTF >= {RTF_OK} and tele >= {TELE_OK:g}%: "
            f"{largest if largest is not None else 'none'}{note}")
        for n, target in TARGETS.items():
            row = next((r for r in rows if int(r[0]) == n), None)
            if row is not None:
                out[-1] += (f"\nN={n}: emulator alone {row[1]}% of one core (target < "
                            f"{target:g}%), RTF {row[2]}, tele {row[5]}%, load avg {row[-1]}")
    if "client" not in skip:
        rows = run_with_client(sizes, args)
        ok = [int(r[0]) for r in rows
              if float(r[4]) >= RTF_OK and float(r[-3]) >= 9.5 and float(r[7]) >= 99]
        out.append("\nEmulator + one MAVSDK client process subscribed to position on every "
                   "vehicle:\n" + table(["N", "found", "discov s", *EMU_HEAD, *CLIENT_HEAD,
                                          "host busy %"], rows)
                   + f"\nlargest N with RTF >= {RTF_OK}, tele >= 99% and >= 9.5 pos/s/vehicle: "
                   f"{max(ok) if ok else 'none'}")
        big = [r for r in rows if int(r[0]) == 250]
        if big:
            out[-1] += (f"; N=250 emulator CPU {big[0][3]}% of one core (target < 50%)")
    if "multi" not in skip:
        ks = [0] + [int(k) for k in args.clients.split(",") if k]
        for k in ks:
            rows, summary = run_multi(args.networks, k, args)
            out.append(f"\n{args.networks * 250} vehicles = {args.networks} emulator processes "
                       f"x 250, {k} with a MAVSDK client (others: drained sink):\n"
                       + table(["proc", "N", *EMU_HEAD, "found", *CLIENT_HEAD], rows)
                       + "\n" + summary)
    print("\n".join(out))
    print(f"\nRTF: simulated/wall s; slip: simulated s/s the pacer gave up; tele %: messages "
          f"sent per vehicle as % of the streams' nominal {NOMINAL:g}/s; host busy %: "
          f"the whole machine's busy CPU (every process, other users included) in % of one "
          f"core, of {100 * (os.cpu_count() or 1)}. MAVSDK warn: WARN/ERROR log lines of the "
          f"client during the window" + "".join(f"\n  MAVSDK said: {w}" for w in WARN_LAST))
    if args.profile:
        profile(max(sizes), args.profile, args)


if __name__ == "__main__":
    main()
