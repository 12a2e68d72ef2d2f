"""Shared benchmark helpers: an emulator in a child process, a UDP sink that drains, host
CPU accounting and table printing (MAVSDK helpers are in _mavsdk.py).

Child processes use the "spawn" start method (MAVSDK and the drain thread must not be
forked). Each child answers "snap" with a snapshot of its own wall clock and process CPU
time (all threads), so rates are measured inside the process that did the work.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import multiprocessing
import os
import platform
import random
import select
import socket
import threading
import time
from collections.abc import Mapping, Sequence
from dataclasses import asdict

from emulator.clock import ClockConfig

LOOPBACK = "127.0.0.1"
_SPAWN = multiprocessing.get_context("spawn")


def free_udp_port() -> int:
    """A UDP port on 127.0.0.1 that the OS says is free right now."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind((LOOPBACK, 0))
        return s.getsockname()[1]


def pct(values: Sequence[float], p: float) -> float:
    """Nearest-rank percentile."""
    s = sorted(values)
    return s[max(0, math.ceil(p / 100.0 * len(s)) - 1)]


def machine_line() -> str:
    return (f"host: {platform.machine()} {os.cpu_count()} CPUs, Python "
            f"{platform.python_version()}, load avg {os.getloadavg()[0]:.2f}")


def host_busy_s() -> float:
    """CPU seconds the whole machine has been busy (all cores, every process), /proc/stat."""
    with open("/proc/stat") as f:
        fields = [int(x) for x in f.readline().split()[1:]]
    idle = fields[3] + fields[4]  # idle + iowait
    return (sum(fields[:8]) - idle) / os.sysconf("SC_CLK_TCK")


def thread_cpu_s() -> dict[int, float]:
    """CPU seconds (user + system) of each live thread of this process, by native thread id
    (Linux: /proc/self/task; a thread that ends while it is read is left out)."""
    tick = os.sysconf("SC_CLK_TCK")
    out: dict[int, float] = {}
    for tid in os.listdir("/proc/self/task"):
        try:
            with open(f"/proc/self/task/{tid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        out[int(tid)] = (int(fields[11]) + int(fields[12])) / tick  # utime, stime
    return out


def table(headers: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    cells = [[str(h) for h in headers]] + [[str(c) for c in r] for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    lines = ["  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def rates(a: Mapping[str, float], b: Mapping[str, float]) -> dict[str, float]:
    """Per-second rates between two snapshots of the same child."""
    wall = b["wall"] - a["wall"]
    out = {"wall": wall, "cpu_pct": 100.0 * (b["cpu"] - a["cpu"]) / wall}
    for key in ("sim", "out", "in", "slipped", "send_errors"):
        if key in a:
            out[key] = (b[key] - a[key]) / wall
    if "warnings" in a:
        out["warn"] = b["warnings"]["count"] - a["warnings"]["count"]
        out["warn_last"] = b["warnings"]["last"]
    if "counts" in a:
        per = [(y - x) / wall for x, y in zip(a["counts"], b["counts"], strict=True)]
        out["cb_mean"] = sum(per) / len(per) if per else 0.0
        out["cb_min"] = min(per) if per else 0.0
    return out


class _Child:
    """A spawned child speaking a tiny command protocol over a Pipe."""

    def __init__(self, target, *args: object) -> None:
        self.conn, child = _SPAWN.Pipe()
        self.proc = _SPAWN.Process(target=target, args=(child, *args), daemon=True)
        self.proc.start()
        child.close()
        self.info: object = None

    def wait_ready(self, timeout_s: float) -> object:
        if not self.conn.poll(timeout_s):
            self.stop()
            raise TimeoutError(f"{self.proc.name} not ready after {timeout_s} s")
        kind, self.info = self.conn.recv()
        if kind != "ready":
            self.stop()
            raise RuntimeError(f"{self.proc.name} failed: {self.info}")
        return self.info

    def ask(self, cmd: str) -> dict:
        self.conn.send(cmd)
        return self.conn.recv()

    def snap(self) -> dict:
        return self.ask("snap")

    def stop(self) -> None:
        if self.proc.is_alive():
            with contextlib.suppress(OSError):
                self.conn.send("stop")
            self.proc.join(20)
            if self.proc.is_alive():
                self.proc.terminate()
                self.proc.join(5)
        self.conn.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


def _serve_commands(conn, snap, stop: asyncio.Event, extra=None) -> None:
    """Answer pipe commands on the running loop: snap, stop, and any in `extra`."""
    loop = asyncio.get_running_loop()

    def on_cmd() -> None:
        try:
            cmd = conn.recv()
        except (EOFError, OSError):
            loop.remove_reader(conn.fileno())
            stop.set()
            return
        if cmd == "stop":
            loop.remove_reader(conn.fileno())
            stop.set()
        elif cmd == "snap":
            conn.send(snap())
        elif extra and cmd in extra:
            conn.send(extra[cmd]())

    loop.add_reader(conn.fileno(), on_cmd)


# ------------------------------------------------------------------------------ emulator
class Emulator(_Child):
    """`Swarm(default_scenario(n))` alone in a child process, sending to 127.0.0.1:api_port.

    Above 250 vehicles the swarm is several MAVLink networks of 250 (system ids 1-250 each,
    emulator.networks), one socket each, in its one process and event loop: network j sends
    to api_port + j.

    Shared-socket topology (one socket for all vehicles, bound to an OS-chosen port), no
    GCS destination. `snap()` returns wall/cpu and the swarm's stats (sim time, datagrams).
    """

    def __init__(self, n: int, api_port: int, *, clock: ClockConfig | None = None,
                 telemetry_hz: Mapping[str, float] | None = None,
                 profile_to: str | None = None, timeout_s: float = 60.0) -> None:
        super().__init__(_emulator_main, n, api_port, clock or ClockConfig(),
                         dict(telemetry_hz or {}), profile_to)
        self.n = n
        self.bind_port = self.wait_ready(timeout_s)

    def events(self) -> list[tuple[int, str, float]]:
        """(vehicle index, kind, sim t_s) of mission_start / mission_complete truth events."""
        return self.ask("events")  # type: ignore[return-value]


def _emulator_main(conn, n, api_port, clock, telemetry_hz, profile_to) -> None:
    prof = None
    if profile_to:  # enabled and disabled by the parent's "profile_on" / "profile_off"
        import cProfile
        prof = cProfile.Profile()
    try:
        asyncio.run(_emulator_serve(conn, n, api_port, clock, telemetry_hz, prof))
    except Exception as error:  # report start-up failures to the parent
        conn.send(("error", repr(error)))
        raise
    finally:
        if prof is not None:
            prof.disable()
            prof.dump_stats(profile_to)


async def _emulator_serve(conn, n, api_port, clock, telemetry_hz, prof=None) -> None:
    from emulator.scenario import default_scenario
    from emulator.swarm import PortPlan, Swarm

    ports = PortPlan(bind_host=LOOPBACK, bind_port=0, api_host=LOOPBACK, api_port=api_port,
                     gcs_port=0)
    swarm = Swarm(default_scenario(n), clock=clock, ports=ports,
                  telemetry_hz=telemetry_hz or None)
    stop = asyncio.Event()

    def snap() -> dict:
        stats = swarm.stats()
        return {"wall": time.monotonic(), "cpu": time.process_time(), **asdict(stats),
                "sim": stats.sim_time_s, "out": stats.frames_out,
                "dgrams": stats.datagrams_out, "in": stats.datagrams_in,
                "slipped": stats.slipped_s,
                "send_errors": sum(e.stats.send_errors for e in swarm.endpoints)}

    def events() -> list[tuple[int, str, float]]:
        kinds = ("mission_start", "mission_complete")
        return [(swarm.fleet.index_by_id[e.vehicle_id], e.kind, e.t_s)
                for e in swarm.recorder.events(kinds=kinds)]

    def profile(on: bool) -> bool:
        if prof is not None:
            (prof.enable if on else prof.disable)()
        return prof is not None

    extra = {"events": events, "profile_on": lambda: profile(True),
             "profile_off": lambda: profile(False)}
    async with swarm:
        conn.send(("ready", swarm.endpoints[0].local_address[1]))
        _serve_commands(conn, snap, stop, extra)
        await stop.wait()


# ---------------------------------------------------------------------------------- sink
class UdpSink:
    """Bound sockets on 127.0.0.1 that a thread drains (so no ICMP unreachable, no drops):
    `ports` consecutive ports from `self.port` (one per network of a swarm above 250).

    The thread wakes every `period_s` and reads everything queued (4 MiB receive buffer),
    so the emulator's sendto never has to wake a sleeping reader (on this VM that costs the
    sender about 5 us per datagram): emulator-only numbers measure the emulator.
    """

    def __init__(self, period_s: float = 0.002, ports: int = 1) -> None:
        self.socks = _bind_consecutive(ports)
        self.sock = self.socks[0]
        self.port = self.sock.getsockname()[1]
        self.count = 0
        self.mark = 0
        self._period_s = period_s
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._drain, daemon=True)
        self._thread.start()

    def _drain(self) -> None:
        buf = bytearray(4096)
        socks = self.socks
        while not self._stop.wait(self._period_s):
            try:
                ready = select.select(socks, [], [], 0)[0] if len(socks) > 1 else socks
                for sock in ready:
                    recv = sock.recv_into
                    try:
                        while True:
                            recv(buf)
                            self.count += 1
                    except BlockingIOError:
                        pass
            except (OSError, ValueError):  # closed
                return

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2)
        for sock in self.socks:
            sock.close()


def _bind_consecutive(count: int) -> list[socket.socket]:
    """`count` non-blocking UDP sockets on consecutive ports of 127.0.0.1 (4 MiB buffers)."""
    for _ in range(200):
        base = 0 if count == 1 else random.randrange(20000, 60000 - count)
        socks: list[socket.socket] = []
        try:
            for j in range(count):
                sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
                socks.append(sock)
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)
                sock.bind((LOOPBACK, base + j if base else 0))
                sock.setblocking(False)
            return socks
        except OSError:
            for sock in socks:
                sock.close()
    raise OSError(f"no {count} consecutive free UDP ports on {LOOPBACK}")
