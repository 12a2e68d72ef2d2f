"""Helpers for the hosted-run tests: a `mavswarm bench run --agent external` process, a short
session with a script of calls for each of its tasks, and the same script played by an agent
in-process (the records a hosted run must reproduce)."""

from __future__ import annotations

import asyncio
import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from agent_contract import AgentTask, AgentTools
from benchmark.authoring.session_file import load_session
from benchmark.running.episode import run_session
from llm_tools.registry import default_registry
from tests.bench_fixtures import small_session, write_json
from tests.cli_fixtures import MAVSWARM, ROOT

__all__ = [
    "CLIENT",
    "COMPARED",
    "SCRIPT",
    "Host",
    "ScriptedAgent",
    "compared",
    "in_process_records",
    "session_file",
    "start_host",
]

CLIENT = str(ROOT / "tests" / "hosted_client.py")
SCRIPT: dict[str, list[list[Any]]] = {
    "t01": [["take_off", {"drone_id": "d3", "altitude_m": 19}],
            ["hover", {"drone_id": "d3", "duration_s": 5}],
            ["finish", {"summary": "holding"}]],
    "t02": [["take_off", {"drone_id": "d1", "altitude_m": 20}],
            ["move_to", {"drone_id": "d1", "x": 472.0, "y": 477.0, "z": 20.0}],
            ["return_home", {"drone_id": "d1"}],
            ["finish", {}]],
}
"""Calls for the two tasks of `session_file` (take off and hold; a round trip)."""

COMPARED = ("session", "task", "trial", "passed", "checks", "checks_total", "checks_passed",
            "finish", "error", "tool_calls", "clock", "sim_time_s", "tokens", "end_state",
            "window_s")
"""The fields of a record that depend on what the agent did, not on who it was or when."""


def compared(records: list[dict[str, Any]]) -> list[dict[str, Any]]:
    return [{k: r.get(k) for k in COMPARED} for r in sorted(records, key=lambda r: r["task"])]


def session_file(folder: Path, name: str = "s.json", **changes: Any) -> Path:
    """An easy area-search session with the two tasks SCRIPT plays."""
    data = small_session(["takeoff_hold", "round_trip_home"])
    return write_json(folder / name, {**data, **changes})


class ScriptedAgent:
    """The script's calls, made in-process through the tool registry (as REST and MCP make
    them)."""

    name = "scripted"

    def __init__(self, script: dict[str, list[list[Any]]]) -> None:
        self.script = script
        self.registry = default_registry()

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        for name, arguments in self.script.get(task.task_id, [["finish", {}]]):
            await self.registry.call(tools, name, arguments)


def in_process_records(path: Path, script: dict[str, list[list[Any]]]) -> list[dict[str, Any]]:
    records: list[dict[str, Any]] = []
    asyncio.run(run_session(load_session(path), ScriptedAgent(script), emit=records.append))
    return records


@dataclass
class Host:
    """A hosted run in a process of its own."""

    proc: subprocess.Popen[str]
    url: str
    seats: list[str]
    out: Path
    printed: str

    def wait(self, timeout_s: float = 60.0) -> tuple[int, str]:
        """Its exit status and everything it printed after starting."""
        rest, _ = self.proc.communicate(timeout=timeout_s)
        return self.proc.returncode, self.printed + rest

    def kill(self) -> None:
        """Stop it if it still runs; what it printed goes to stderr (shown if the test fails)."""
        if self.proc.poll() is None:
            self.proc.kill()
            rest, _ = self.proc.communicate(timeout=10)
            sys.stderr.write(f"the hosted run printed:\n{self.printed}{rest or ''}")


def start_host(sessions: list[Path], out: Path, *extra: str) -> Host:
    """`mavswarm bench run --agent external` on a free port, once it prints its endpoint."""
    proc = subprocess.Popen(
        [*MAVSWARM, "bench", "run", "--agent", "external", "--sessions", *map(str, sessions),
         "--out", str(out), "--port", "0", *extra],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=ROOT,
        env={**os.environ, "PYTHONUNBUFFERED": "1"})
    assert proc.stdout is not None
    seen = []
    for line in proc.stdout:
        seen.append(line)
        if "MultiUAV-Plat clients" in line:
            break
    printed = "".join(seen)
    found = re.search(r"endpoint (http://\S+)", printed)
    if found is None:
        proc.kill()
        raise AssertionError(f"the hosted run printed no endpoint:\n{printed}")
    return Host(proc, found.group(1), re.findall(r"seat-[\w-]+", printed), out, printed)


def run_client(surface: str, host: Host, script_path: Path, *extra: str
               ) -> subprocess.CompletedProcess[str]:
    """tests/hosted_client.py against `host`, to the end of the run."""
    return subprocess.run([sys.executable, CLIENT, surface, host.url, str(script_path),
                           *extra], capture_output=True, text=True, timeout=120, cwd=ROOT)
