"""MAVSDK-Python 3.x (gRPC, with its bundled mavsdk_server) flies an official-style example
script against the emulator over real UDP, in its own venv (`.venv-mavsdk3`, made by
`./dev`); the ground truth shows the orbit it asked for."""

from __future__ import annotations

import asyncio
import os
import sys
from pathlib import Path

import numpy as np
import pytest

from emulator.scenario import default_scenario

ROOT = Path(__file__).resolve().parent.parent
PYTHON3 = ROOT / ".venv-mavsdk3" / "bin" / "python"
EXAMPLES = Path(__file__).resolve().parent / "mavsdk3_examples"

pytestmark = [
    pytest.mark.mavsdk,
    pytest.mark.skipif(not PYTHON3.exists(),
                       reason="no .venv-mavsdk3 (MAVSDK-Python 3.x): ./dev creates it"),
]


def _free_tcp_port() -> int:
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


async def test_do_orbit_example_with_mavsdk_python_3(swarm_factory) -> None:
    swarm = await swarm_factory(1, scenario=default_scenario(1), speed=5.0)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}  # its own mavsdk only
    proc = await asyncio.create_subprocess_exec(
        str(PYTHON3), str(EXAMPLES / "do_orbit.py"), str(swarm.ports.api_port),
        str(_free_tcp_port()), env=env, stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.STDOUT)
    try:
        out, _ = await asyncio.wait_for(proc.communicate(), 90.0)
    finally:
        if proc.returncode is None:
            proc.kill()
            await proc.wait()
    text = out.decode(errors="replace")
    assert proc.returncode == 0, text
    assert "-- Landed" in text, text
    orbits = swarm.recorder.events("d1", kinds="orbit")
    assert len(orbits) == 1 and orbits[0].data["radius_m"] == pytest.approx(10.0)
    cx, cy, _ = orbits[0].data["center_m"]
    assert (cx, cy) == pytest.approx((0.0, 20.0), abs=0.05)
    # on the circle once it got there: 10 m from the centre
    t_orbit = orbits[0].t_s
    left = [e.t_s for e in swarm.recorder.events("d1", t0_s=t_orbit, kinds="mode")
            if e.data["previous"] == "orbit"]
    t_end = left[0] if left else swarm.fleet.now_s
    rows = swarm.recorder.trajectory("d1", t_orbit + 8.0, t_end)
    r = np.hypot(rows[:, 1] - cx, rows[:, 2] - cy)
    assert len(rows) > 10 and np.abs(r - 10.0).max() < 0.3
    assert not swarm.fleet.autopilots[0].in_air
    assert sys.executable != str(PYTHON3)
