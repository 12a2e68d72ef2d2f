"""`mavswarm up` as a user runs it: prints connection URLs, flies, stops cleanly on Ctrl-C."""

from __future__ import annotations

import signal
import socket
import time
from pathlib import Path

import pytest
from pymavlink.dialects.v20 import common as mavlink

from emulator.truth import TruthRecorder
from tests.cli_fixtures import read_until, run_in_process, start_up
from tests.ports import unused_udp_port


@pytest.mark.slow
def test_up_prints_urls_answers_a_client_and_stops_cleanly(tmp_path: Path):
    api, gcs, bind = unused_udp_port(), unused_udp_port(), unused_udp_port()
    truth = tmp_path / "run.truth.npz"
    proc = start_up("--drones", "3", "--speed", "5", "--bind-host", "127.0.0.1",
                  "--bind-port", str(bind), "--api-port", str(api), "--gcs-port", str(gcs),
                  "--truth-out", str(truth))
    try:
        text = read_until(proc, "MAVProxy")
        assert f"udpin://0.0.0.0:{api}" in text
        assert f"udpout:127.0.0.1:{bind}" in text
        assert "3 vehicles" in text
        # A client listening on the API port receives heartbeats from systems 1..3.
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            sock.bind(("127.0.0.1", api))
            sock.settimeout(5.0)
            mav = mavlink.MAVLink(None)
            systems: set[int] = set()
            deadline = time.monotonic() + 5.0
            while len(systems) < 3 and time.monotonic() < deadline:
                data, _ = sock.recvfrom(4096)
                for msg in mav.parse_buffer(data) or []:
                    if msg.get_type() == "HEARTBEAT" and msg.get_srcComponent() == 1:
                        assert msg.autopilot == mavlink.MAV_AUTOPILOT_PX4
                        systems.add(msg.get_srcSystem())
        assert systems == {1, 2, 3}
    finally:
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=20)
    assert proc.returncode == 0, out
    assert "stopping after" in out and "ground truth written" in out
    log = TruthRecorder.load(truth)
    assert log.vehicle_ids == ("d1", "d2", "d3") and log.end_t_s > 0


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--drones", "0"], "--drones must be at least 1"),
        (["--speed", "-3"], "speed must be within"),
        (["--session", "/nonexistent/session.json"], "session.json"),
        (["--per-vehicle-ports", "--drones", "20", "--api-port", "14540", "--gcs-port", "14550"],
         "include the GCS port 14550"),
    ],
)
def test_bad_options_give_a_clear_error(args: list[str], message: str, tmp_path: Path):
    proc = run_in_process("up", *args, cwd=tmp_path)
    assert proc.returncode == 2
    assert message in proc.stderr, proc.stderr
