"""Instructions the physics core executes for the stepped benchmark's missions: a count that
does not depend on the machine's speed or load, so a change of a few percent shows where CPU
time cannot (on a shared 2-core machine the same code's CPU time swings by a third).

    ./dev perf core_instructions [--drones 10] [--physics-hz 50] [--runs 3] [--slice 50]
    ./dev perf core_instructions --session area_search-easy-1

The missions of `stepped_speedup --core` (emulator.flight.Fleet in 50-step slices as a lockstep
swarm runs them, `--slice 250` as one without lockstep does; no MAVLink)
fly in two child processes under valgrind's callgrind, one flying them once and one `--runs`
times; their difference over runs - 1 is the instructions of one flight, start-up and imports
left out. Printed with the truth digest, which must not change when the physics is only made
faster. `--session ID` counts instead the whole process of `truth_digest --sessions ID`: the
oracle over every task of that session in lockstep, every action over MAVLink (start-up and
MAVSDK's threads included), with its truth and records digests. Needs valgrind
(`apt-get install valgrind`).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import machine_line

from emulator.flight.native import COMPILED

HERE = os.path.abspath(__file__)


def child(drones: int, hz: float, runs: int, slice_steps: int) -> None:
    """Fly the missions `runs` times; print the truth digest of the last flight."""
    from stepped_speedup import fly_core

    for i in range(runs):
        result = fly_core(drones, hz, digest=i == runs - 1, slice_steps=slice_steps)
    print(f"digest {result['digest']}")


def callgrind(*args: str) -> tuple[int, str]:
    """Run `python ARGS` under callgrind (a fixed hash seed: the same dict and set layouts);
    the instructions it executed and its standard output."""
    out = subprocess.run(
        ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null", sys.executable,
         *args], capture_output=True, text=True, check=True,
        env={**os.environ, "PYTHONHASHSEED": "0"})
    found = re.search(r"Collected : (\d+)", out.stderr)
    if found is None:
        raise RuntimeError(f"callgrind gave no count:\n{out.stderr[-2000:]}")
    return int(found.group(1)), out.stdout


def counted(drones: int, hz: float, runs: int, slice_steps: int) -> tuple[int, str]:
    """Instructions of a child flying `runs` times, and its digest."""
    count, out = callgrind(HERE, "--child", str(runs), "--drones", str(drones),
                           "--physics-hz", str(hz), "--slice", str(slice_steps))
    digest = re.search(r"digest (\w+)", out)
    if digest is None:
        raise RuntimeError(f"the child printed no digest:\n{out[-2000:]}")
    return count, digest.group(1)


def session_count(session: str) -> None:
    """The instructions of `truth_digest --sessions SESSION`, and its digests."""
    count, out = callgrind(os.path.join(os.path.dirname(HERE), "truth_digest.py"),
                           "--sessions", session)
    row = [line for line in out.splitlines() if line.startswith(session)]
    if not row:
        raise RuntimeError(f"truth_digest printed no row for {session}:\n{out[-2000:]}")
    _, tasks, sim_s, truth, records, _cpu = row[-1].split()
    print(f"instructions: {count / 1e9:.2f} billion for {tasks} tasks ({sim_s} simulated s); "
          f"truth sha256 {truth}, records sha256 {records}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--drones", type=int, default=10)
    p.add_argument("--physics-hz", type=float, default=50.0)
    p.add_argument("--runs", type=int, default=3, help="flights in the second child (>= 2)")
    p.add_argument("--slice", type=int, default=50,
                   help="steps per Fleet.run (50: a lockstep swarm's; 250: one's without)")
    p.add_argument("--session", metavar="ID",
                   help="count the oracle over this benchmark session instead (lockstep)")
    p.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.child is not None:
        child(args.drones, args.physics_hz, args.child, args.slice)
        return
    if shutil.which("valgrind") is None:
        sys.exit("core_instructions needs valgrind (apt-get install valgrind)")
    if args.session:
        print(f"core_instructions --session {args.session}: the oracle over its tasks in "
              "lockstep under callgrind, the whole process")
        print(machine_line(), flush=True)
        session_count(args.session)
        return
    runs = max(2, args.runs)
    print(f"core_instructions: {args.drones} vehicles, {args.physics_hz:g} Hz, the stepped "
          f"benchmark's missions on the core in slices of {args.slice} steps under callgrind "
          f"(1 and {runs} flights); compiled: "
          f"{', '.join(sorted(COMPILED)) or 'none'}")
    print(machine_line(), flush=True)
    with ThreadPoolExecutor(2) as pool:
        once, more = pool.map(lambda k: counted(args.drones, args.physics_hz, k, args.slice),
                              (1, runs))
    per_flight = (more[0] - once[0]) / (runs - 1)
    print(f"instructions per flight: {per_flight / 1e6:.1f} million; truth sha256 {more[1]}"
          + ("" if more[1] == once[1] else f" (the single flight: {once[1]})"))


if __name__ == "__main__":
    main()
