"""A real Mosquitto broker for the MQTT tests: its own process on a free port, with the
shipped ACL (mqtt_bus/mosquitto/mavswarm.acl) and a password file for the users `mavswarm`
(the swarm side), `operator` and `agent`. Never the system service."""

from __future__ import annotations

import getpass
import shutil
import socket
import subprocess
import time
from pathlib import Path

from tests.ports import unused_tcp_port

__all__ = ["PASSWORDS", "Broker", "mosquitto_binary"]

ROOT = Path(__file__).resolve().parent.parent
ACL = ROOT / "mqtt_bus" / "mosquitto" / "mavswarm.acl"
PASSWORDS = {"mavswarm": "swarm-pw", "operator": "operator-pw", "agent": "agent-pw"}


def mosquitto_binary() -> str | None:
    return shutil.which("mosquitto") or next(
        (p for p in ("/usr/sbin/mosquitto", "/usr/local/sbin/mosquitto") if Path(p).exists()),
        None)


class Broker:
    """`start()`, `stop()` (SIGTERM) and `kill()` (SIGKILL); `start()` again reuses the
    port."""

    def __init__(self, folder: Path) -> None:
        binary = mosquitto_binary()
        if binary is None:
            raise RuntimeError("mosquitto is not installed (.ci/run installs it)")
        self.binary = binary
        self.folder = folder
        self.port = unused_tcp_port()
        self.proc: subprocess.Popen[bytes] | None = None
        passwd = folder / "passwd"
        passwd.write_text("".join(f"{user}:{pw}\n" for user, pw in PASSWORDS.items()))
        passwd.chmod(0o600)
        subprocess.run([shutil.which("mosquitto_passwd") or "mosquitto_passwd", "-U",
                        str(passwd)], check=True, capture_output=True, timeout=30)
        self.conf = folder / "mosquitto.conf"
        self.conf.write_text(
            # as root, mosquitto would drop to user "mosquitto", who cannot read tmp_path
            f"user {getpass.getuser()}\n"
            f"listener {self.port} 127.0.0.1\nallow_anonymous false\n"
            f"password_file {passwd}\nacl_file {ACL}\npersistence false\n"
            "max_queued_messages 100000\nset_tcp_nodelay true\n")
        self.log = folder / "mosquitto.log"

    def url(self, user: str = "mavswarm", prefix: str = "mavswarm") -> str:
        return f"mqtt://{user}:{PASSWORDS[user]}@127.0.0.1:{self.port}/{prefix}"

    def start(self, timeout_s: float = 15.0) -> None:
        with self.log.open("ab") as log:
            self.proc = subprocess.Popen([self.binary, "-c", str(self.conf)], stdout=log,
                                         stderr=subprocess.STDOUT)
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError(f"mosquitto exited: {self.log.read_text()[-2000:]}")
            try:
                with socket.create_connection(("127.0.0.1", self.port), timeout=0.5):
                    return
            except OSError:
                time.sleep(0.05)
        raise RuntimeError(f"mosquitto did not listen on {self.port}")

    def kill(self) -> None:
        """SIGKILL: the broker dies without a word (and, without persistence, forgets every
        retained message)."""
        if self.proc is not None and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(timeout=10)
        self.proc = None

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=10)
        self.proc = None
