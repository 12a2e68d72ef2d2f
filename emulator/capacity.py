"""How many emulated vehicles this machine can run, checked before `mavswarm up` starts any.

A MAVLink network's system ids 1-250 make at most 250 vehicles; a swarm of more is several
networks (emulator.networks), and one process holds up to 10,000 vehicles (40 networks) in
real time with full telemetry (docs/performance.md); more run as several processes, their
networks shared out evenly. Per machine: one process per CPU core this process may use, and
each process's memory (a base plus a share per vehicle, from `up` measured at 250 vehicles)
within the memory available; both measured when the command starts.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

from emulator.networks import VEHICLES_PER_NETWORK, network_count

__all__ = ["MAX_VEHICLES_PER_NETWORK", "VEHICLES_PER_PROCESS", "CapacityError", "Machine",
           "check_capacity", "network_memory_mb", "process_networks"]

MAX_VEHICLES_PER_NETWORK = VEHICLES_PER_NETWORK  # system ids 1-250 (0: broadcast, 251-255: GCS)
VEHICLES_PER_PROCESS = 40 * VEHICLES_PER_NETWORK  # held in real time by one process
PROCESS_BASE_MB = 80.0  # one `up` process without vehicles (interpreter, numpy, asyncio)
VEHICLE_MB = 0.15  # each vehicle on top (250 vehicles: 117 MB resident after start)
MEMORY_SHARE = 0.8  # of the memory available at start, the most the swarm may take


class CapacityError(ValueError):
    """The swarm asked for cannot run on this machine (the message says why)."""


@dataclass(frozen=True)
class Machine:
    """What `up` may use here: CPU cores and the memory available, in MB."""

    cores: int
    memory_available_mb: float

    @classmethod
    def measure(cls) -> Machine:
        """This process's CPU cores (its affinity) and the memory available now."""
        try:
            cores = len(os.sched_getaffinity(0))
        except AttributeError:  # not Linux
            cores = os.cpu_count() or 1
        return cls(max(cores, 1), _available_mb())

    def describe(self) -> str:
        return (f"{self.cores} CPU core{'s' if self.cores != 1 else ''} and "
                f"{self.memory_available_mb / 1024:.1f} GB of memory available")


def _available_mb() -> float:
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) / 1024.0
    except (OSError, ValueError, IndexError):
        pass
    return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE") / 2**20


def network_memory_mb(vehicles: int) -> float:
    """The memory one process of `vehicles` takes, estimated."""
    return PROCESS_BASE_MB + VEHICLE_MB * vehicles


def process_networks(vehicles: int) -> list[range]:
    """The networks (0, 1, ...) each process of a swarm of `vehicles` runs: as few processes
    as hold them (VEHICLES_PER_PROCESS each), the networks shared out evenly in order."""
    networks = network_count(vehicles)
    processes = math.ceil(vehicles / VEHICLES_PER_PROCESS)
    base, extra = divmod(networks, processes)
    plan, first = [], 0
    for p in range(processes):
        count = base + (1 if p < extra else 0)
        plan.append(range(first, first + count))
        first += count
    return plan


def check_capacity(vehicles: int, machine: Machine) -> int:
    """The number of processes `vehicles` need; CapacityError (one line, with the limits and
    the numbers they come from) when this machine cannot run them."""
    networks = network_count(vehicles)
    needed = math.ceil(vehicles / VEHICLES_PER_PROCESS)
    per_process = min(vehicles, max(len(r) for r in process_networks(vehicles))
                      * VEHICLES_PER_NETWORK)
    budget_mb = MEMORY_SHARE * machine.memory_available_mb
    by_memory = int(budget_mb // network_memory_mb(per_process))
    processes = min(machine.cores, by_memory)
    most = processes * VEHICLES_PER_PROCESS if processes else max(
        0, min(VEHICLES_PER_PROCESS, int((budget_mb - PROCESS_BASE_MB) // VEHICLE_MB)))
    if needed <= processes:
        return needed
    split = (f"MAVLink system ids 1-{VEHICLES_PER_NETWORK} make that {networks} networks of "
             f"up to {VEHICLES_PER_NETWORK} vehicles, {needed} processes of up to "
             f"{VEHICLES_PER_PROCESS} vehicles; " if networks > 1 else "")
    raise CapacityError(
        f"--drones {vehicles} cannot run here: {split}this machine has "
        f"{machine.describe()} at start, room for {processes} process"
        f"{'es' if processes != 1 else ''} (one per core, about "
        f"{network_memory_mb(per_process):.0f} MB each within {MEMORY_SHARE:.0%} of the "
        f"memory): at most {most} drones here")
