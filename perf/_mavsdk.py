"""MAVSDK helpers for the benchmarks: executor sizing, quiet logs, discovery, and a client
process that subscribes to position on every vehicle and counts the callbacks."""

from __future__ import annotations

import asyncio
import concurrent.futures
import time

from _common import LOOPBACK, _Child, _serve_commands


def set_executor(n: int) -> None:
    """mavsdk.asyncio runs each blocking call in the default executor: make it big."""
    asyncio.get_running_loop().set_default_executor(
        concurrent.futures.ThreadPoolExecutor(n + 16))


async def wait_for_systems(mavsdk, n: int, t0: float, timeout_s: float,
                           poll_s: float = 0.01) -> tuple[list, float, float]:
    """Poll until n systems are is_connected and has_autopilot. Returns (systems sorted by
    sysid, seconds from t0 to the first system seen, seconds from t0 to all n ready)."""
    t_first = float("nan")
    deadline = t0 + timeout_s
    while True:
        systems = await mavsdk.get_systems()
        now = time.monotonic()
        if systems and t_first != t_first:
            t_first = now - t0
        ready = [s for s in systems if await s.is_connected() and await s.has_autopilot()]
        if len(ready) >= n or now > deadline:
            ids = [await s.get_system_id() for s in ready]
            order = sorted(range(len(ready)), key=ids.__getitem__)
            return [ready[i] for i in order], t_first, now - t0
        await asyncio.sleep(poll_s)


WARNINGS = {"count": 0, "last": ""}  # MAVSDK WARN/ERROR log lines of this process


def quiet_mavsdk() -> None:
    """Silence MAVSDK's log (one DEBUG line per component discovered); count WARN/ERROR
    lines in WARNINGS instead (e.g. "Dropping subscription callbacks ...")."""
    from mavsdk import LogLevel, log_subscribe

    def on_log(level, msg, _file, _line) -> bool:
        if level >= LogLevel.WARN:
            WARNINGS["count"] += 1
            WARNINGS["last"] = msg.splitlines()[0] if msg else ""
        return True
    log_subscribe(on_log)


def warnings_line() -> str:
    w = WARNINGS
    return f"MAVSDK warnings/errors: {w['count']}" + (f" (last: {w['last']})" if w["count"] else "")


def new_mavsdk():
    from mavsdk.asyncio import ComponentType, Configuration, Mavsdk
    quiet_mavsdk()
    return Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))


class Client(_Child):
    """A MAVSDK process on udpin://127.0.0.1:port that discovers n systems and subscribes
    to position on every one. api "asyncio": TelemetryAsync.subscribe_position async
    generators (one task per vehicle); "callback": the plain plugin's C callback."""

    def __init__(self, port: int, n: int, *, api: str = "asyncio") -> None:
        super().__init__(_client_main, port, n, api)
        self.n = n

    def ready(self, timeout_s: float = 60.0) -> dict:
        return self.wait_ready(timeout_s)  # type: ignore[return-value]


def _client_main(conn, port, n, api) -> None:
    try:
        asyncio.run(_client_serve(conn, port, n, api))
    except Exception as error:
        conn.send(("error", repr(error)))
        raise


async def _client_serve(conn, port, n, api) -> None:
    set_executor(n)
    stop = asyncio.Event()
    async with new_mavsdk() as mavsdk:
        t0 = time.monotonic()
        await mavsdk.add_any_connection(f"udpin://{LOOPBACK}:{port}")
        systems, _, t_all = await wait_for_systems(mavsdk, n, t0, timeout_s=30.0)
        counts = [0] * len(systems)
        keep: list = []
        if api == "callback":
            from mavsdk.plugins.telemetry import Telemetry

            def make_cb(i):
                def cb(_pos, _ud):
                    counts[i] += 1
                return cb
            for i, system in enumerate(systems):
                plugin = Telemetry(system._system)
                plugin.subscribe_position(make_cb(i))
                keep.append(plugin)
        else:
            from mavsdk.asyncio.plugins.telemetry import TelemetryAsync

            async def follow(i, telemetry):
                async for _ in telemetry.subscribe_position():
                    counts[i] += 1
            for i, system in enumerate(systems):
                telemetry = TelemetryAsync(system)
                keep.append(asyncio.create_task(follow(i, telemetry)))
                keep.append(telemetry)
        conn.send(("ready", {"found": len(systems), "discovery_s": t_all}))
        _serve_commands(conn, lambda: {"wall": time.monotonic(), "cpu": time.process_time(),
                                       "counts": list(counts), "warnings": dict(WARNINGS)}, stop)
        await stop.wait()
        for task in keep:
            if isinstance(task, asyncio.Task):
                task.cancel()
