"""What starting the `mavswarm` command costs before it does anything: a fresh interpreter
running `python -m mavswarm COMMAND --help`, per command, as wall and CPU time (median of the
repeats) and the number of modules it imported. Every test and user that runs the command
pays this once per process.

    ./dev perf cli_startup [--repeat 5]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COMMANDS = [[], ["up"], ["bench", "run"], ["serve"], ["mcp"], ["replay"], ["mqtt-bridge"]]
_COUNT_MODULES = ("import runpy, sys\n"
                  "sys.argv = ['mavswarm', *sys.argv[1:]]\n"
                  "try:\n"
                  "    runpy.run_module('mavswarm', run_name='__main__')\n"
                  "except SystemExit:\n"
                  "    pass\n"
                  "print(len(sys.modules), file=sys.stderr)\n")


def _once(command: list[str]) -> tuple[float, float]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "mavswarm", *command, "--help"], cwd=ROOT,
                   env=_env(), stdout=subprocess.DEVNULL, check=True)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def _modules(command: list[str]) -> int:
    done = subprocess.run([sys.executable, "-c", _COUNT_MODULES, *command, "--help"], cwd=ROOT,
                          env=_env(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                          text=True, check=True)
    return int(done.stderr.split()[-1])


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": os.pathsep.join(
        filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}


def main(repeat: int) -> None:
    _once([])  # compiled bytecode in place before timing
    print(f"mavswarm start-up, median of {repeat} (load average "
          f"{os.getloadavg()[0]:.1f} at the start)")
    print(f"{'command':<30} {'wall s':>7} {'CPU s':>7} {'modules':>8}")
    for command in COMMANDS:
        times = [_once(command) for _ in range(repeat)]
        wall = statistics.median(t[0] for t in times)
        cpu = statistics.median(t[1] for t in times)
        name = " ".join(["mavswarm", *command, "--help"])
        print(f"{name:<30} {wall:7.2f} {cpu:7.2f} {_modules(command):8d}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5, help="runs per command")
    main(parser.parse_args().repeat)
