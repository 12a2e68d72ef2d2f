"""Processes that used MAVSDK end through normal interpreter shutdown with their own status:
a user's script that flies a swarm through the gateway, one that leaves its fleet open with a
primitive still in flight, and a pytest run (tests/conftest.py) whose test failed."""

from __future__ import annotations

import asyncio
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
CRASH_SIGNS = ("Fatal Python error", "Segmentation fault", "terminate called", "Aborted",
               "core dumped", "Exception ignored")

# A user's script: a swarm on loopback UDP, the gateway connected to it, a take-off, a second
# drone still climbing (`open`: the fleet is left open and the primitive in flight), then the
# end of the script.
SCRIPT = """
import asyncio, sys
from emulator.clock import ClockConfig
from emulator.scenario import default_scenario
from emulator.services import SwarmServices
from emulator.swarm import PortPlan, Swarm
from mavlink_gateway import FleetConnection, Gateway, profiles_from_scenario
from tests.ports import unused_udp_port

async def main(leave_open):
    scenario = default_scenario(2)
    port = unused_udp_port()
    swarm = Swarm(scenario, clock=ClockConfig(speed=20.0),
                  ports=PortPlan(bind_host="127.0.0.1", bind_port=0, api_port=port, gcs_port=0))
    await swarm.start()
    fleet = await FleetConnection.connect(f"udpin://127.0.0.1:{port}",
                                          profiles_from_scenario(scenario),
                                          scenario.world.origin)
    gateway = Gateway(fleet.drones, SwarmServices(swarm))
    print((await gateway.take_off("d1", 5.0)).status, flush=True)
    if leave_open:
        asyncio.get_running_loop().create_task(gateway.take_off("d2", 30.0))
        await asyncio.sleep(0.3)
        return
    await fleet.close()
    await swarm.close()

asyncio.run(main(sys.argv[1] == "open"))
print("script ended", flush=True)
"""


def _run(args: list[str], timeout_s: float = 300) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONFAULTHANDLER": "1"}
    return subprocess.run([sys.executable, *args], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=timeout_s, check=False)


def _assert_clean(done: subprocess.CompletedProcess[str], status: int) -> None:
    output = done.stdout + done.stderr
    assert done.returncode == status, output[-3000:]
    assert not [sign for sign in CRASH_SIGNS if sign in output], output[-3000:]


@pytest.mark.slow
@pytest.mark.mavsdk
@pytest.mark.parametrize("ending", ["closed", "open"])
def test_a_script_that_flies_through_the_gateway_exits_normally(ending: str) -> None:
    for _ in range(3):
        done = _run(["-c", SCRIPT, ending])
        _assert_clean(done, 0)
        assert done.stdout.split() == ["ok", "script", "ended"]


FAILING = """
import atexit
atexit.register(print, "interpreter shut down", flush=True)  # not run after os._exit

async def test_flies_then_fails(swarm_factory, mavsdk_client):
    swarm = await swarm_factory(2)
    async with mavsdk_client(swarm.ports.api_port, 2) as systems:
        assert len(systems) == 2
    assert {verdict}
"""


@pytest.mark.slow
@pytest.mark.mavsdk
@pytest.mark.parametrize(("verdict", "status"), [("False", 1), ("True", 0)])
def test_a_test_run_that_used_mavsdk_exits_with_pytests_status(
        tmp_path: Path, verdict: str, status: int) -> None:
    """The suite's own conftest (as a plugin), a test that flies with MAVSDK: pytest's exit
    status, reached through normal interpreter shutdown (exit handlers run)."""
    test_file = tmp_path / "test_verdict.py"
    test_file.write_text(textwrap.dedent(FAILING.format(verdict=verdict)))
    # --confcutdir: collection starts at tmp_path instead of listing every parent folder
    # (the shared /tmp can hold tens of thousands of entries).
    done = _run(["-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "tests.conftest",
                 "--rootdir", str(tmp_path), "--confcutdir", str(tmp_path), "-c", os.devnull,
                 "-o", "asyncio_mode=auto", str(test_file)])
    _assert_clean(done, status)
    assert ("1 failed" if status else "1 passed") in done.stdout
    assert done.stdout.rstrip().endswith("interpreter shut down")


@pytest.mark.mavsdk
async def test_close_lets_mavsdk_calls_still_running_on_worker_threads_end_first(
        swarm_factory) -> None:
    """A primitive cancelled or timed out leaves its blocking MAVSDK call running on a worker
    thread: close() waits for it before MAVSDK goes away. A request for a parameter nobody has
    blocks a worker for MAVSDK's whole timeout (3 s)."""
    from mavlink_gateway import FleetConnection, profiles_from_scenario

    swarm = await swarm_factory(1)
    fleet = await FleetConnection.connect(f"udpin://127.0.0.1:{swarm.ports.api_port}",
                                          profiles_from_scenario(swarm.fleet.scenario),
                                          swarm.fleet.scenario.world.origin)
    request = asyncio.ensure_future(fleet.drones["d1"].param.get_param_float("NO_SUCH_PRM"))
    await asyncio.sleep(0.2)
    request.cancel()  # the awaiting side gives up; the worker thread does not
    started = time.monotonic()
    await fleet.close()
    assert time.monotonic() - started > 1.5
