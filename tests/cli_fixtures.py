"""The shipped `mavswarm` command, as tests run it: the console script installed beside this
interpreter."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

__all__ = ["MAVSWARM", "ROOT", "read_until", "start_up"]

ROOT = Path(__file__).resolve().parents[1]
_SCRIPT = Path(sys.executable).with_name("mavswarm")
MAVSWARM: list[str] = [str(_SCRIPT)] if _SCRIPT.exists() else [sys.executable, "-m", "mavswarm"]
"""argv prefix of the `mavswarm` command."""


def start_up(*args: str) -> subprocess.Popen[str]:
    """`mavswarm up ARGS` in a subprocess, its stdout and stderr merged and unbuffered."""
    return subprocess.Popen(
        [*MAVSWARM, "up", *args],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )


def read_until(proc: subprocess.Popen[str], needle: str, timeout_s: float = 20.0) -> str:
    """Everything `proc` printed up to the line holding `needle` (AssertionError if it ends
    or `timeout_s` passes first)."""
    assert proc.stdout is not None
    seen = []
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            break
        seen.append(line)
        if needle in line:
            return "".join(seen)
    raise AssertionError(f"{needle!r} not printed; got:\n{''.join(seen)}")
