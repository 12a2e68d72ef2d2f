"""A swarm of more than 250 vehicles: MAVLink networks of 250 side by side, one socket each.

Vehicle k is in network k // 250 with system id k % 250 + 1 (emulator.networks); each
network is a swarm of its own on the wire (its own socket, destination port api_port + j),
while one fleet, one scheduler and one telemetry batch serve them all.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

from emulator.clock import ClockConfig
from emulator.flight.fleet import Fleet
from emulator.mavlink.codec import mavlink
from emulator.mavlink.frames import frame_batch
from emulator.mavlink.telemetry import FleetTelemetry
from emulator.networks import VEHICLES_PER_NETWORK, network_count, network_of, system_id
from emulator.scenario import default_scenario
from emulator.swarm import PortPlan, Swarm
from tests.cli_fixtures import read_until, start_up
from tests.mavlink_client import LoopErrors, MavClient
from tests.test_telemetry_batch import _consecutive_udp_sockets

CMD_REQUEST_MESSAGE = 512
UID_BASE = 0x4D53570000000000  # AUTOPILOT_VERSION.uid = UID_BASE + fleet index + 1


def test_system_ids_repeat_per_network_of_250() -> None:
    assert [system_id(k) for k in (0, 249, 250, 251, 499, 500)] == [1, 250, 1, 2, 250, 1]
    assert [network_of(k) for k in (0, 249, 250, 9_999)] == [0, 0, 1, 39]
    assert [network_count(n) for n in (1, 250, 251, 10_000)] == [1, 1, 2, 40]
    fleet = Fleet(default_scenario(260))
    assert [ap.params["MAV_SYS_ID"] for ap in fleet.autopilots[248:252]] == [249, 250, 1, 2]
    assert FleetTelemetry(fleet).system_ids[248:252].tolist() == [249, 250, 1, 2]


@pytest.mark.parametrize(("ports", "message"), [
    (PortPlan(bind_port=30000, api_port=14540, gcs_port=14550), "API ports 14540-14579 overlap"),
    (PortPlan(bind_port=14560, api_port=14540, gcs_port=0), "bind ports 14560-14599 overlap"),
    (PortPlan(bind_port=65500, api_port=14540, gcs_port=0), "bind ports 65500-65539, beyond"),
])
def test_ports_of_several_networks_are_checked(ports: PortPlan, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        ports.check(40 * VEHICLES_PER_NETWORK)
    PortPlan(bind_port=14580, api_port=14540, gcs_port=14550).check(VEHICLES_PER_NETWORK)


def test_frame_batch_in_a_given_row_order() -> None:
    fleet = Fleet(default_scenario(6))
    telemetry = FleetTelemetry(fleet)
    ks = np.arange(6)
    parts = [telemetry.part(0, ks), telemetry.part(33, ks[:4])]
    plain = frame_batch(parts)
    order = np.array([9, 0, 8, 1, 7, 2, 6, 3, 5, 4])
    shuffled = frame_batch(parts, order)
    assert [shuffled.frame(i) for i in range(10)] == [plain.frame(int(j)) for j in order]


async def test_networks_carry_their_own_vehicles_and_route_by_system_id() -> None:
    n = VEHICLES_PER_NETWORK + 10
    errors = LoopErrors().install()
    swarm = Swarm(default_scenario(n), clock=ClockConfig(speed=1.0),
                  ports=PortPlan(bind_host="127.0.0.1", bind_port=0, api_port=0, gcs_port=0))
    await swarm.start()
    clients: list[MavClient] = []
    try:
        assert len(swarm.endpoints) == 2
        for endpoint in swarm.endpoints:
            client = await MavClient.connect(endpoint.local_address)
            client.send(client.mav.heartbeat_encode(6, 8, 0, 0, 4, 3))
            clients.append(client)
        expected = [set(range(1, 251)), set(range(1, 11))]
        for _ in range(50):  # every vehicle's 1 Hz heartbeat, each on its own network
            await asyncio.sleep(0.1)
            beats = [{r.msg.get_srcSystem() for r in c.received
                      if r.msg.get_type() == "HEARTBEAT"} for c in clients]
            if beats == expected:
                break
        assert beats == expected
        first, second = clients
        assert first.bad_in == second.bad_in == 0
        # system 3 is vehicle 2 on the first network and vehicle 252 on the second
        for client, k in ((first, 2), (second, 252)):
            client.send(client.mav.command_long_encode(3, 1, CMD_REQUEST_MESSAGE, 0, 148,
                                                       0, 0, 0, 0, 0, 0))
            version = await client.wait_for("AUTOPILOT_VERSION", system=3, timeout=3.0)
            assert version.uid == UID_BASE + k + 1
        second.send(second.mav.param_request_read_encode(11, 1, b"MAV_SYS_ID", -1))
        await second.expect_none("PARAM_VALUE", system=11, within=0.5)  # nobody there
        assert swarm.stats().unroutable == 1
        assert swarm.stats().internal_errors == 0
        assert not errors.errors, errors.describe()
    finally:
        for client in clients:
            client.close()
        with contextlib.suppress(Exception):
            await swarm.close()
        errors.uninstall()


@pytest.mark.slow
def test_up_runs_networks_of_250_in_one_process() -> None:
    receivers = _consecutive_udp_sockets(2)  # the two networks' API ports
    api = receivers[0].getsockname()[1]
    proc = start_up("--drones", "260", "--no-truth", "--bind-host", "127.0.0.1",
                    "--bind-port", "0", "--api-port", str(api), "--gcs-port", "0")
    try:
        text = read_until(proc, "MAVProxy", timeout_s=60.0)
        assert "[nets 0-1] 260 vehicles" in text
        assert f"udpin://0.0.0.0:{api} .. {api + 1} (one per network of 250)" in text
        assert "each network's port chosen by the OS" in text
        expected = [set(range(1, 251)), set(range(1, 11))]
        seen: list[set[int]] = [set(), set()]
        parsers = [mavlink.MAVLink(None), mavlink.MAVLink(None)]
        deadline = time.monotonic() + 30.0
        while seen != expected and time.monotonic() < deadline:
            time.sleep(0.05)
            for j, sock in enumerate(receivers):
                with contextlib.suppress(BlockingIOError):
                    while True:
                        for m in parsers[j].parse_buffer(sock.recv(65535)) or []:
                            if m.get_type() == "HEARTBEAT" and m.get_srcComponent() == 1:
                                seen[j].add(m.get_srcSystem())
        assert seen == expected
    finally:
        out = _stopped(proc, signal.SIGINT)
        for sock in receivers:
            sock.close()
    assert proc.returncode == 0, out
    assert "stopping after" in out


@pytest.mark.slow
def test_sigterm_stops_every_network_process_as_ctrl_c_does() -> None:
    proc = start_up("--drones", "260", "--no-truth", "--bind-host", "127.0.0.1",
                    "--bind-port", "0", "--api-port", "0", "--gcs-port", "0")
    children: list[int] = []
    try:
        read_until(proc, "MAVProxy", timeout_s=60.0)
        children = _children(proc.pid)
        assert children, "the networks run in a process of their own"
    finally:
        out = _stopped(proc, signal.SIGTERM)
    assert proc.returncode == 0, out
    assert "[nets 0-1] stopping after" in out
    assert not [pid for pid in children if Path(f"/proc/{pid}").exists()]


def _stopped(proc: subprocess.Popen[str], sig: signal.Signals) -> str:
    """Send `sig` and wait up to 90 s for the process to end; what it printed. A process that
    does not stop is killed with its children (none is left behind) and the output says so."""
    proc.send_signal(sig)
    try:
        out, _ = proc.communicate(timeout=90)
    except subprocess.TimeoutExpired:
        for child in _children(proc.pid):
            os.kill(child, signal.SIGKILL)
        proc.kill()
        out, _ = proc.communicate(timeout=10)
        out += f"\n(did not stop within 90 s of {sig.name})"
    return out


def _children(pid: int) -> list[int]:
    """The process ids whose parent is pid (Linux /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            with contextlib.suppress(OSError):
                if int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1]) == pid:
                    found.append(int(entry.name))
    return found
