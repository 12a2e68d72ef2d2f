"""The bus from the command line, on a real Mosquitto: `mavswarm up --mqtt` killed with
SIGKILL reads offline (the broker's Last Will), a benchmark run publishes every record that
results.jsonl holds in order, `serve --mqtt` refuses commands while a task runs for an agent,
`mqtt-bridge` puts a swarm of another process on the bus, and bad options exit 2."""

from __future__ import annotations

import asyncio
import os
import signal
import subprocess
from pathlib import Path

import pytest

from benchmark.running.results import read_records
from tests.bench_fixtures import small_session, write_json
from tests.cli_fixtures import MAVSWARM, read_until, run_in_process, start_up
from tests.mosquitto_broker import Broker
from tests.mqtt_helpers import broker, listener, request
from tests.ports import unused_tcp_port, unused_udp_port

pytestmark = [pytest.mark.mavsdk]
__all__ = ["broker"]


def _stop(proc: subprocess.Popen[str]) -> None:
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=10)


async def test_kill_9_of_the_swarm_reads_offline(broker: Broker) -> None:
    proc = start_up("--drones", "2", "--no-truth", "--bind-port", str(unused_udp_port()),
                    "--api-port", str(unused_udp_port()), "--gcs-port", "0",
                    "--mqtt", broker.url(), "--mqtt-session", "killed")
    try:
        read_until(proc, "MQTT: ", timeout_s=60)
        async with listener(broker, "agent", "mavswarm/killed/#") as agent:
            await agent.wait_for(lambda g: g.kind == "status"
                                 and g.payload["status"] == "online")
            await agent.wait_for(lambda g: g.kind == "osd" and g.payload["drone"] == "d2")
            proc.send_signal(signal.SIGKILL)
            proc.wait(timeout=10)
            offline = await agent.wait_for(lambda g: g.kind == "status"
                                           and g.payload["status"] == "offline",
                                           timeout_s=30)
            assert offline.payload == {"status": "offline", "session": "killed"}
        async with listener(broker, "agent", "mavswarm/killed/status") as late:
            got = await late.wait_for(lambda g: True)
            assert got.retain and got.payload["status"] == "offline"
    finally:
        _stop(proc)


async def _bench_run(session: Path, out: Path, broker: Broker
                     ) -> subprocess.CompletedProcess[str]:
    """`bench run --agent oracle --mqtt` (its main, in this process, on a thread: this loop
    keeps reading the bus meanwhile)."""
    return await asyncio.wait_for(asyncio.to_thread(
        run_in_process, "bench", "run", "--agent", "oracle", "--sessions", str(session),
        "--out", str(out), "--mqtt", broker.url(), cwd=out.parent), 300)


@pytest.mark.slow
async def test_a_benchmark_run_publishes_every_record_in_order(broker: Broker,
                                                               tmp_path: Path) -> None:
    session = write_json(tmp_path / "s.json",
                         small_session(["takeoff_hold", "new_home", "altitude_change"]))
    out = tmp_path / "run-a"
    async with listener(broker, "operator", "mavswarm/bench/run-a/#") as op:
        run = await _bench_run(session, out, broker)
        assert run.returncode == 0, (run.stdout + run.stderr)[-3000:]
        records = read_records(out / "results.jsonl")
        await op.wait_for(lambda g: g.kind == "progress" and g.payload.get("finished"))
    published = [g.payload for g in op.of("tasks")]
    assert [p["key"] for p in published] == [r["key"] for r in records]
    for p, r in zip(published, records, strict=True):
        assert "checks" not in p  # the hidden check tree stays in results.jsonl
        assert p == {k: v for k, v in r.items() if k != "checks"}
    final = op.of("progress")[-1].payload
    assert final["tasks"] == len(records) == final["records_in_results"] == 3
    assert final["passed"] == sum(r["passed"] for r in records)
    assert "MQTT: " in run.stdout and " 0 dropped" in run.stdout
    # re-running the finished run resumes nothing and publishes the file again, in order
    async with listener(broker, "operator", "mavswarm/bench/run-a/tasks") as again:
        run = await _bench_run(session, out, broker)
        assert run.returncode == 0, (run.stdout + run.stderr)[-3000:]
        await again.wait_for(lambda g: g.payload["key"] == records[-1]["key"])
    assert [g.payload["key"] for g in again.got] == [r["key"] for r in records]
    assert read_records(out / "results.jsonl") == records


async def test_serve_refuses_commands_while_a_task_runs_and_accepts_them_in_free_flight(
        broker: Broker, tmp_path: Path) -> None:
    world = small_session([])
    tasked = write_json(tmp_path / "tasked.json", {**small_session(["takeoff_hold"]),
                                                   "id": "tasked"})
    free = write_json(tmp_path / "free.json", {**world, "id": "free"})
    port = unused_tcp_port()
    proc = subprocess.Popen(
        [*MAVSWARM, "serve", "--sessions", str(tasked), str(free), "--port", str(port),
         "--mqtt", broker.url()], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
        text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        read_until(proc, "REST API on", timeout_s=120)
        async with listener(broker, "operator", "mavswarm/+/status") as ready:
            for name in ("tasked", "free"):  # online: listening for commands
                await ready.wait_for(lambda g, n=name: g.payload["session"] == n
                                     and g.payload["status"] == "online")
        async with listener(broker, "operator", "mavswarm/+/+/services_reply") as op:
            drone = world["drones"][0]["id"]
            refused = await request(op, "mavswarm/tasked", drone, "take_off",
                                    altitude_m=5.0)
            assert refused["status"] == "rejected"
            assert "benchmark task t01" in refused["message"]
            flown = await request(op, "mavswarm/free", drone, "take_off", altitude_m=5.0)
            assert flown["status"] == "ok", flown
        async with listener(broker, "agent", "mavswarm/tasked/+/state") as agent:
            state = await agent.wait_for(lambda g: g.payload["drone"] == drone)
            assert state.payload["flight_state"] == "on_ground"
    finally:
        _stop(proc)


async def test_the_bridge_puts_a_swarm_of_another_process_on_the_bus(broker: Broker) -> None:
    api = unused_udp_port()
    swarm = start_up("--drones", "2", "--no-truth", "--bind-port", str(unused_udp_port()),
                     "--api-port", str(api), "--gcs-port", "0")
    bridge = subprocess.Popen(
        [*MAVSWARM, "mqtt-bridge", "--mavlink", f"udpin://127.0.0.1:{api}", "--drones", "2",
         "--mqtt", broker.url(), "--mqtt-session", "sitl", "--mqtt-osd-hz", "5"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"})
    try:
        read_until(bridge, "bridging 2 drones", timeout_s=90)
        async with listener(broker, "operator", "mavswarm/sitl/#") as op:
            await op.wait_for(lambda g: g.kind == "osd" and g.payload["drone"] == "d2")
            took = await request(op, "mavswarm/sitl", "d1", "take_off", altitude_m=5.0)
            assert took["status"] == "ok" and took["message"] == "d1 took off to 5.0 m"
            await op.wait_for(lambda g: g.kind == "osd" and g.payload["drone"] == "d1"
                              and g.payload["position"]["altitude_m"] > 4.0)
            radio = await request(op, "mavswarm/sitl", "d1", "send_message",
                                  to_drone_id="d2", text="hi")
            assert radio["status"] == "rejected" and "no drone-to-drone radio" in \
                radio["message"]
    finally:
        _stop(bridge)
        _stop(swarm)
    out = bridge.stdout.read() if bridge.stdout else ""
    assert "messages published" in out


def test_a_bad_mqtt_url_exits_2_with_the_reason(tmp_path: Path) -> None:
    # every URL rule is in test_mqtt_units; here, that `up` reports one and starts nothing
    out = run_in_process("up", "--drones", "1", "--no-truth", "--mqtt", "mqtt://host/a+b",
                         cwd=tmp_path)
    assert out.returncode == 2, out.stderr
    assert "cannot be an MQTT topic level" in out.stderr and "vehicles" not in out.stdout


def test_bench_run_with_a_bad_mqtt_url_runs_nothing(tmp_path: Path) -> None:
    out = run_in_process("bench", "run", "--agent", "noop", "--out", str(tmp_path / "r"),
                         "--mqtt", "mqtts://h/x?ca=1&bad=2", cwd=tmp_path)
    assert out.returncode == 2 and "unknown option 'bad'" in out.stderr, out.stderr
    assert not (tmp_path / "r").exists()
