"""The `mavswarm` command line is assembled from each package's parts, and a command loads only
its own: each command built alone takes the same options and runs the same function as in
the whole command line, and `up` starts without the benchmark, the REST server or FastAPI."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys

import pytest

from mavswarm.cli import COMMANDS, build_parser
from tests.cli_fixtures import ROOT, run_in_process


def _command(parser: argparse.ArgumentParser, name: str) -> argparse.ArgumentParser:
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices[name]


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_a_command_built_alone_is_the_command_of_the_whole_line(name: str) -> None:
    whole, alone = _command(build_parser(), name), _command(build_parser(name), name)
    assert alone.format_help() == whole.format_help()
    assert alone.get_default("run") is whole.get_default("run")


def test_the_whole_line_lists_every_command() -> None:
    sub = next(a for a in build_parser()._actions
               if isinstance(a, argparse._SubParsersAction))
    assert set(sub.choices) == set(COMMANDS)


def test_an_unknown_command_is_refused_naming_every_command(tmp_path) -> None:
    proc = run_in_process("frob", cwd=tmp_path)
    assert proc.returncode == 2
    assert all(name in proc.stderr for name in COMMANDS), proc.stderr


def test_up_loads_neither_the_benchmark_nor_the_server() -> None:
    probe = ("import json, sys\n"
             "from mavswarm.cli import build_parser\n"
             "build_parser('up').parse_args(['up', '--drones', '2'])\n"
             "print(json.dumps(sorted(sys.modules)))\n")
    out = subprocess.run([sys.executable, "-c", probe], cwd=ROOT, capture_output=True,
                         text=True, timeout=60, check=True).stdout
    loaded = set(json.loads(out))
    assert "emulator.swarm" in loaded and "console.cli" in loaded
    assert not {m for m in loaded if m == "benchmark" or m.startswith(("benchmark.", "fastapi"))}
