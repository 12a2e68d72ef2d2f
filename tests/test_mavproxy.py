"""MAVProxy (the PyPI package, headless, commands piped on stdin) against a running swarm."""

from __future__ import annotations

import asyncio
import contextlib
import importlib.util
import os
import re
import shutil
import sys
import time
from pathlib import Path

import pytest

from emulator.flight.modes import FlightMode
from emulator.flight.params import PARAM_DEFINITIONS
from tests.mavlink_client import running_swarm

pytestmark = pytest.mark.slow


def mavproxy_script() -> Path | None:
    beside = Path(sys.executable).parent / "mavproxy.py"
    if beside.exists():
        return beside
    found = shutil.which("mavproxy.py")
    return Path(found) if found else None


class MavProxy:
    """A mavproxy.py subprocess: write commands to it, wait for text in its output."""

    def __init__(self, proc: asyncio.subprocess.Process) -> None:
        self.proc = proc
        self.output = ""
        self._changed = asyncio.Event()
        self._reader = asyncio.create_task(self._read())

    @classmethod
    async def start(cls, port: int, state_dir: Path) -> MavProxy:
        script = mavproxy_script()
        assert script is not None
        env = {k: v for k, v in os.environ.items() if k != "DISPLAY"}
        env["HOME"] = str(state_dir)  # no ~/.mavinit.scr of the user's
        proc = await asyncio.create_subprocess_exec(
            sys.executable, str(script), f"--master=udpout:127.0.0.1:{port}",
            f"--state-basedir={state_dir}", stdin=asyncio.subprocess.PIPE,
            stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.STDOUT, cwd=state_dir,
            env=env,
        )
        return cls(proc)

    async def _read(self) -> None:
        assert self.proc.stdout is not None
        while chunk := await self.proc.stdout.read(4096):
            self.output += chunk.decode(errors="replace")
            self._changed.set()

    async def command(self, line: str) -> int:
        """Send one command line; returns the output offset before it."""
        assert self.proc.stdin is not None
        mark = len(self.output)
        self.proc.stdin.write(line.encode() + b"\n")
        await self.proc.stdin.drain()
        return mark

    async def expect(self, pattern: str, *, since: int = 0, timeout: float = 20.0) -> re.Match:
        deadline = time.monotonic() + timeout
        while True:
            found = re.search(pattern, self.output[since:])
            if found:
                return found
            if self.proc.returncode is not None or time.monotonic() > deadline:
                raise AssertionError(
                    f"MAVProxy never printed {pattern!r}; output:\n{self.output[-3000:]}"
                )
            self._changed.clear()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._changed.wait(), 0.2)

    async def stop(self) -> None:
        if self.proc.returncode is None:
            with contextlib.suppress(Exception):
                assert self.proc.stdin is not None
                self.proc.stdin.close()
            self.proc.terminate()
            try:
                await asyncio.wait_for(self.proc.wait(), 5.0)
            except TimeoutError:
                self.proc.kill()
                await self.proc.wait()
        await self._reader


@pytest.mark.skipif(importlib.util.find_spec("MAVProxy") is None or mavproxy_script() is None,
                    reason="MAVProxy is not installed (pip install 'MAVProxy>=1.8', in the dev "
                           "extra)")
async def test_mavproxy_detects_arms_and_switches_mode(tmp_path: Path) -> None:
    # real time: at a higher speed the 10 s pre-flight auto-disarm would race the checks
    async with running_swarm(1, speed=1.0) as (swarm, client):
        client.close()  # MAVProxy is the only ground station from here on
        ap = swarm.fleet.autopilots[0]
        _host, port = swarm.endpoints[0].local_address
        mavproxy = await MavProxy.start(port, tmp_path)
        try:
            await mavproxy.expect(r"Detected vehicle 1:1")
            await mavproxy.expect(r"online system 1")
            count = await mavproxy.expect(r"Received (\d+) parameters", timeout=30.0)
            assert int(count.group(1)) == len(PARAM_DEFINITIONS)

            mark = await mavproxy.command("arm throttle")
            await mavproxy.expect(r"COMPONENT_ARM_DISARM: ACCEPTED", since=mark)
            await mavproxy.expect(r"\bARMED\b", since=mark)
            assert ap.armed
            assert [e.kind for e in swarm.recorder.events("d1", kinds=("arm",))] == ["arm"]

            # PX4 mode change the way that works in MAVProxy 1.8.75: AUTO.TAKEOFF
            mark = await mavproxy.command("long DO_SET_MODE 157 4 2")
            await mavproxy.expect(r"DO_SET_MODE: ACCEPTED", since=mark)
            await mavproxy.expect(r"TAKEOFF", since=mark)
            assert ap.in_air
            assert ap.mode in (FlightMode.TAKEOFF, FlightMode.HOLD)
            assert swarm.recorder.events("d1", kinds=("takeoff",))
        finally:
            await mavproxy.stop()
