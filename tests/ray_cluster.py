"""A real Ray cluster on this machine's loopback range, for tests and benchmarks: a head node at
127.0.0.2 and worker nodes at 127.0.0.3, 127.0.0.4, ..., each `ray start --block` in a process
group of its own (so one node can be killed alone, and nothing else is touched), every port
from the tests' allocator. The cluster has a fresh token of its own (Ray's token
authentication): a driver joins it with `cluster.env` in its environment.

Loopback addresses other than 127.0.0.1: Ray replaces 127.0.0.1 and localhost in a cluster
address by the machine's outward address, and every node and driver here must stay on loopback.
"""

from __future__ import annotations

import contextlib
import os
import secrets
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType

from tests.ports import unused_tcp_port

__all__ = ["LocalRayCluster", "RayNode"]

RAY = Path(sys.executable).with_name("ray")
STARTED = "Ray runtime started"
WORKER_PORTS = 16  # ports a node's worker processes (and drivers) may bind


def _port() -> int:
    # Ray binds its servers on every address: a port must be free on all of them.
    return unused_tcp_port("0.0.0.0")


def _session_members(sid: int) -> list[int]:
    """The processes of session `sid` (Linux /proc): a node's `ray start` began the session,
    and every process of the node stays in it, though its workers lead process groups of
    their own."""
    members = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            with contextlib.suppress(OSError):  # gone meanwhile
                if os.getsid(int(entry)) == sid:
                    members.append(int(entry))
    return members


def _signal_all(pids: list[int], sig: signal.Signals) -> None:
    for pid in pids:
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, sig)


@dataclass
class RayNode:
    ip: str
    process: subprocess.Popen[bytes]
    log: Path

    @property
    def alive(self) -> bool:
        return self.process.poll() is None

    def kill(self) -> None:
        """SIGKILL every process of this node (its raylet, object store, workers) at once:
        all are stopped first, so no worker goes on running a task after its raylet died
        (a task's results go straight to its driver, raylet or not)."""
        members = _session_members(self.process.pid)
        _signal_all(members, signal.SIGSTOP)
        _signal_all(members, signal.SIGKILL)
        self.process.wait(timeout=30)
        self._kill_rest()

    def stop(self, grace_s: float = 5.0) -> None:
        """SIGTERM the node's process group; SIGKILL whatever of the node is left after
        grace_s (workers outlive a stopped parent)."""
        if self.alive:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(self.process.pid, signal.SIGTERM)
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.process.wait(timeout=grace_s)
        with contextlib.suppress(ProcessLookupError):
            os.killpg(self.process.pid, signal.SIGKILL)
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.process.wait(timeout=grace_s)
        self._kill_rest()

    def _kill_rest(self) -> None:
        """SIGKILL any process of the node's session still there (one forked meanwhile)."""
        for _ in range(10):
            members = [p for p in _session_members(self.process.pid) if p != self.process.pid]
            if not members:
                return
            _signal_all(members, signal.SIGKILL)
            time.sleep(0.05)


class LocalRayCluster:
    """`with LocalRayCluster(head_cpus=1) as cluster: cluster.add_node(1); cluster.address`"""

    def __init__(self, *, head_cpus: int = 1, object_store_bytes: int = 80_000_000,
                 start_timeout_s: float = 90.0) -> None:
        if not RAY.exists():
            raise RuntimeError(f"no `ray` command beside {sys.executable}")
        self.head_cpus = head_cpus
        self.object_store_bytes = object_store_bytes
        self.start_timeout_s = start_timeout_s
        self.nodes: list[RayNode] = []
        self.address = ""
        token = secrets.token_hex(32)
        self.env = {"RAY_AUTH_MODE": "token", "RAY_AUTH_TOKEN": token,
                    "RAY_USAGE_STATS_ENABLED": "0", "RAY_enable_metrics_collection": "0"}
        """What a driver's environment needs to join this cluster."""
        # Short: Ray's Unix socket paths live under it and must stay below 108 bytes.
        self.temp_dir = Path(tempfile.mkdtemp(prefix="ray-", dir="/tmp"))

    def __enter__(self) -> LocalRayCluster:
        try:
            self.start()
        except BaseException:
            self.stop()
            raise
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.stop()

    def _node_args(self, ip: str, num_cpus: int) -> list[str]:
        ports = ",".join(str(_port()) for _ in range(WORKER_PORTS))
        return ["--block", "--node-ip-address", ip, "--num-cpus", str(num_cpus),
                "--object-store-memory", str(self.object_store_bytes),
                "--node-manager-port", str(_port()),
                "--object-manager-port", str(_port()),
                "--worker-port-list", ports,
                "--dashboard-agent-listen-port", str(_port()),
                "--dashboard-agent-grpc-port", str(_port()),
                "--metrics-export-port", str(_port()),
                "--runtime-env-agent-port", str(_port()),
                "--disable-usage-stats", "--log-style", "record"]

    def _launch(self, ip: str, args: list[str]) -> RayNode:
        log = self.temp_dir / f"node-{ip}.log"
        with log.open("wb") as out:
            process = subprocess.Popen([str(RAY), "start", *args], stdout=out,
                                       stderr=subprocess.STDOUT, start_new_session=True,
                                       env={**os.environ, **self.env})
        node = RayNode(ip, process, log)
        self.nodes.append(node)
        deadline = time.monotonic() + self.start_timeout_s
        while STARTED not in log.read_text(errors="replace"):
            if not node.alive or time.monotonic() > deadline:
                raise RuntimeError(f"ray node {ip} did not start:\n{log.read_text()[-3000:]}")
            time.sleep(0.2)
        return node

    def start(self) -> None:
        """Start the head node (127.0.0.2)."""
        ip = "127.0.0.2"
        port = _port()
        self.address = f"{ip}:{port}"
        self._launch(ip, ["--head", "--port", str(port), "--include-dashboard", "false",
                          "--dashboard-port", str(_port()),
                          "--temp-dir", str(self.temp_dir),
                          *self._node_args(ip, self.head_cpus)])

    def add_node(self, num_cpus: int = 1) -> RayNode:
        """Start a worker node on the next loopback address and join it to the head."""
        ip = f"127.0.0.{len(self.nodes) + 2}"
        return self._launch(ip, ["--address", self.address, *self._node_args(ip, num_cpus)])

    def stop(self) -> None:
        """Stop every node, workers before the head, and remove the temporary folder."""
        for node in reversed(self.nodes):
            node.stop()
        shutil.rmtree(self.temp_dir, ignore_errors=True)
