"""The MQTT bus under load: 250 drones' osd at 10 Hz through a real Mosquitto.

    ./dev perf mqtt_bus [--drones 250] [--osd-hz 10] [--window 15] [--commands 200]

The swarm (`Swarm(default_scenario(N))`, real time, 50 Hz physics, telemetry to no UDP
destination) runs in a child process twice: alone, then with `swarm_session_bus` publishing
every drone's osd at --osd-hz. Reported per run: the child's CPU (all threads, % of one
core) and RTF over the window; the bus's extra CPU is the difference. A subscriber in this
process (user `operator`) receives every osd and stamps it on arrival; the child stamps every
physics step, so the latency is arrival minus the wall time of the step whose state the osd
carries (CLOCK_MONOTONIC is shared by the processes). Then --commands `drone_state` requests
go over MQTT one after another and their round trips are timed (the first, which links the
gateway to the drone over MAVSDK, is not counted).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import multiprocessing
import os
import socket
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from _common import machine_line, pct, table

from tests.mosquitto_broker import PASSWORDS, Broker

_SPAWN = multiprocessing.get_context("spawn")


def _child(conn, n: int, url: str | None, osd_hz: float) -> None:  # type: ignore[no-untyped-def]
    asyncio.run(_child_main(conn, n, url, osd_hz))


async def _child_main(conn, n: int, url: str | None, osd_hz: float) -> None:  # type: ignore[no-untyped-def]
    import contextlib

    from emulator.clock import ClockConfig
    from emulator.scenario import default_scenario
    from emulator.swarm import PortPlan, Swarm
    from mqtt_bus.swarm_bus import swarm_session_bus
    from mqtt_bus.url import parse_broker_url

    swarm = Swarm(default_scenario(n), clock=ClockConfig(speed=1.0),
                  ports=PortPlan(bind_host="127.0.0.1", bind_port=0, api_port=0, gcs_port=0))
    stamps: dict[float, float] = {}
    fleet = swarm.fleet
    step = fleet.step

    def stamped_step() -> None:
        step()
        stamps[round(fleet.now_s, 3)] = time.monotonic()

    fleet.step = stamped_step  # type: ignore[method-assign]
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()

    def answer() -> None:
        message = conn.recv()
        if message == "snap":
            s = swarm.stats()
            conn.send({"wall": time.monotonic(), "cpu": time.process_time(),
                       "sim": fleet.now_s, "slipped": s.slipped_s})
        elif message == "stamps":
            conn.send(dict(stamps))
        elif message == "bus":
            conn.send(bus.report() if bus else "")
        else:
            stop.set()

    async with swarm:
        bus = None
        async with contextlib.AsyncExitStack() as stack:
            if url is not None:
                bus = await stack.enter_async_context(
                    swarm_session_bus(parse_broker_url(url), "bench", swarm, osd_hz=osd_hz))
                await bus.connection.wait_connected(10.0)
            loop.add_reader(conn.fileno(), answer)
            conn.send("ready")
            await stop.wait()
            loop.remove_reader(conn.fileno())


class Child:
    def __init__(self, n: int, url: str | None, osd_hz: float) -> None:
        self.conn, theirs = _SPAWN.Pipe()
        self.proc = _SPAWN.Process(target=_child, args=(theirs, n, url, osd_hz), daemon=True)
        self.proc.start()
        if not self.conn.poll(120):
            raise RuntimeError("the swarm process did not start")
        assert self.conn.recv() == "ready"

    def ask(self, what: str):  # type: ignore[no-untyped-def]
        self.conn.send(what)
        return self.conn.recv()

    def stop(self) -> None:
        self.conn.send("stop")
        self.proc.join(30)
        if self.proc.is_alive():
            self.proc.kill()


def _subscriber(port: int, arrivals: list[tuple[float, bytes]]):  # type: ignore[no-untyped-def]
    """A paho client on its own thread that stamps every osd on arrival (lighter than an
    asyncio client, so the stamps measure the bus rather than this process)."""
    import paho.mqtt.client as paho

    client = paho.Client(paho.CallbackAPIVersion.VERSION2, client_id="bench-osd")
    client.username_pw_set("operator", PASSWORDS["operator"])

    def on_message(_c, _u, m) -> None:  # type: ignore[no-untyped-def]
        arrivals.append((time.monotonic(), m.payload))

    def on_connect(c, _u, _f, _rc, _p) -> None:  # type: ignore[no-untyped-def]
        c.subscribe("mavswarm/bench/+/osd")

    client.on_message = on_message
    client.on_connect = on_connect
    client.connect("127.0.0.1", port)
    client.socket().setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    client.loop_start()
    return client


async def _measure(child: Child, window_s: float, broker: Broker | None, n: int
                   ) -> dict[str, object]:
    arrivals: list[tuple[float, bytes]] = []
    result: dict[str, object] = {}
    sub = _subscriber(broker.port, arrivals) if broker is not None else None
    await asyncio.sleep(3.0)  # warm up
    a = child.ask("snap")
    mark = len(arrivals)
    await asyncio.sleep(window_s)
    b = child.ask("snap")
    wall = b["wall"] - a["wall"]
    result["cpu_pct"] = 100.0 * (b["cpu"] - a["cpu"]) / wall
    result["rtf"] = (b["sim"] - a["sim"]) / wall
    result["slipped_s"] = b["slipped"] - a["slipped"]
    if sub is not None and broker is not None:
        await asyncio.sleep(1.0)  # what is still on its way
        sub.loop_stop()
        sub.disconnect()
        window = [(t, p) for t, p in arrivals[mark:]
                  if a["sim"] <= json.loads(p)["time_s"] <= b["sim"]]
        result["osd_per_s_per_drone"] = len(window) / (b["sim"] - a["sim"]) / n
        stamps = child.ask("stamps")
        latencies = []
        for t, payload in window:
            step_wall = stamps.get(round(json.loads(payload)["time_s"], 3))
            if step_wall is not None:
                latencies.append((t - step_wall) * 1000.0)
        result["latency_ms"] = latencies
        result["rtt_ms"] = await _commands(broker.port)
    return result


COMMANDS = 200


async def _commands(port: int) -> list[float]:
    """Round trips of `drone_state` requests over MQTT, one after another."""
    import aiomqtt
    replies: dict[str, float] = {}
    arrived = asyncio.Event()
    async with aiomqtt.Client("127.0.0.1", port, username="operator",
                              password=PASSWORDS["operator"],
                              socket_options=[(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)]
                              ) as client:

        async def collect() -> None:
            async for m in client.messages:
                replies[json.loads(m.payload)["id"]] = time.monotonic()  # type: ignore[arg-type]
                arrived.set()

        task = asyncio.create_task(collect())
        await client.subscribe("mavswarm/bench/d1/services_reply", qos=1)
        rtts = []
        for i in range(COMMANDS + 1):
            rid = f"c{i}"
            arrived.clear()
            sent = time.monotonic()
            await client.publish("mavswarm/bench/d1/services",
                                 json.dumps({"id": rid, "tool": "drone_state"}), qos=1)
            async with asyncio.timeout(60.0 if i == 0 else 10.0):
                while rid not in replies:
                    await arrived.wait()
                    arrived.clear()
            if i > 0:
                rtts.append((replies[rid] - sent) * 1000.0)
        task.cancel()
    return rtts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--drones", type=int, default=250)
    parser.add_argument("--osd-hz", type=float, default=10.0)
    parser.add_argument("--window", type=float, default=15.0)
    parser.add_argument("--commands", type=int, default=200)
    args = parser.parse_args()
    global COMMANDS
    COMMANDS = args.commands
    with tempfile.TemporaryDirectory() as folder:
        broker = Broker(Path(folder))
        broker.start()
        try:
            rows = []
            runs = {}
            for mode in ("alone", "bus"):
                url = broker.url() if mode == "bus" else None
                child = Child(args.drones, url, args.osd_hz)
                try:
                    runs[mode] = asyncio.run(_measure(
                        child, args.window, broker if mode == "bus" else None, args.drones))
                    if mode == "bus":
                        print(child.ask("bus"))
                finally:
                    child.stop()
                r = runs[mode]
                rows.append([mode, f"{r['cpu_pct']:.1f}", f"{r['rtf']:.4f}",
                             f"{r['slipped_s']:.2f}",
                             f"{r.get('osd_per_s_per_drone', 0.0):.2f}"])
        finally:
            broker.stop()
    print(f"{args.drones} drones, osd {args.osd_hz:g} Hz, window {args.window:g} s, "
          "Mosquitto on loopback")
    print(table(["swarm", "CPU % of one core", "RTF", "slip s", "osd/s per drone"], rows))
    bus = runs["bus"]
    extra = float(bus["cpu_pct"]) - float(runs["alone"]["cpu_pct"])  # type: ignore[arg-type]
    print(f"extra CPU of publishing: {extra:.1f} % of one core")
    lat = bus["latency_ms"]
    rtt = bus["rtt_ms"]
    assert isinstance(lat, list) and isinstance(rtt, list)
    if lat:
        print(f"physics step -> subscriber: p50 {pct(lat, 50):.1f} ms, p95 {pct(lat, 95):.1f} "
              f"ms, max {max(lat):.1f} ms ({len(lat)} osd messages)")
    if rtt:
        print(f"command round trip (drone_state over MQTT): p50 {pct(rtt, 50):.2f} ms, "
              f"p95 {pct(rtt, 95):.2f} ms ({len(rtt)} requests)")
    print(machine_line() + " (a machine shared with other engineers' work)")


if __name__ == "__main__":
    main()
