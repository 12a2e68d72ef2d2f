"""Where a swarm listens and sends: its bind, API and GCS port bases, and the checks that
the ports of every network (or every vehicle, with per-vehicle ports) fit and do not overlap."""

from __future__ import annotations

from dataclasses import dataclass

from emulator.networks import network_count

__all__ = ["PortPlan"]


@dataclass(frozen=True, slots=True)
class PortPlan:
    """Where the swarm listens and sends.

    Shared (default): one socket bound at `bind_port` for every vehicle, sending to
    `api_port` (MAVSDK: ``udpin://0.0.0.0:14540``) and `gcs_port` (QGroundControl).
    Per-vehicle: vehicle k binds `bind_port + k - 1` and sends to `api_port + k - 1` and
    `gcs_port`, PX4 multi-instance style. 0 for `api_port`/`gcs_port` disables that target.
    Shared with more than 250 vehicles: one socket per MAVLink network of 250
    (emulator.networks); network j binds `bind_port + j` (all OS-chosen when `bind_port` is 0)
    and sends to `api_port + j` and `gcs_port + j`, as if each were a swarm of its own.
    """

    bind_host: str = "0.0.0.0"
    bind_port: int = 0
    api_host: str = "127.0.0.1"
    api_port: int = 14540
    gcs_port: int = 14550
    per_vehicle: bool = False

    def check(self, n: int) -> None:
        for name in ("bind_port", "api_port", "gcs_port"):
            port = getattr(self, name)
            if not 0 <= port <= 65535:
                raise ValueError(f"{name} {port} outside 0..65535")
        if not self.per_vehicle:
            self._check_networks(network_count(n))
            return
        if self.bind_port == 0:
            raise ValueError("per-vehicle ports need an explicit bind port base")
        binds = range(self.bind_port, self.bind_port + n)
        apis = range(self.api_port, self.api_port + n) if self.api_port else range(0)
        if self.gcs_port and self.gcs_port in apis:
            raise ValueError(
                f"{n} vehicles need API ports {apis.start}-{apis.stop - 1}, which include the "
                f"GCS port {self.gcs_port}; choose another --api-port"
            )
        if set(binds) & (set(apis) | {self.gcs_port}):
            raise ValueError(
                f"bind ports {binds.start}-{binds.stop - 1} overlap destination ports"
            )
        if binds.stop - 1 > 65535 or (apis and apis.stop - 1 > 65535):
            raise ValueError("port range exceeds 65535")


    def _check_networks(self, count: int) -> None:
        """Shared sockets: `count` networks at bind/api/gcs port + j (see the class)."""
        def span(port: int) -> range:
            return range(port, port + count) if port else range(0)

        binds, apis, gcs = span(self.bind_port), span(self.api_port), span(self.gcs_port)
        for name, ports in (("bind", binds), ("API", apis), ("GCS", gcs)):
            if ports and ports.stop - 1 > 65535:
                raise ValueError(f"{count} networks need {name} ports {ports.start}-"
                                 f"{ports.stop - 1}, beyond 65535")
        if set(binds) & (set(apis) | set(gcs)):
            if count == 1:
                raise ValueError(f"bind port {self.bind_port} is also a destination port")
            raise ValueError(f"{count} networks' bind ports {binds.start}-{binds.stop - 1} "
                             "overlap their destination ports")
        if count > 1 and set(apis) & set(gcs):
            raise ValueError(f"{count} networks' API ports {apis.start}-{apis.stop - 1} "
                             f"overlap their GCS ports {gcs.start}-{gcs.stop - 1}")

    def connection_urls(self, networks: int, vehicles: int, bound_ports: list[int]
                        ) -> list[str]:
        """Where MAVSDK, QGroundControl and MAVProxy connect to a swarm of `vehicles` in
        `networks` networks whose sockets are bound at `bound_ports` (empty before start)."""
        urls = []
        if networks > 1 and not self.per_vehicle:  # networks of 250 (emulator.networks)
            if self.api_port:
                urls.append(f"MAVSDK:         udpin://0.0.0.0:{self.api_port} .. "
                            f"{self.api_port + networks - 1} (one per network of 250)")
            if self.gcs_port:
                urls.append(f"QGroundControl: UDP {self.gcs_port} .. "
                            f"{self.gcs_port + networks - 1}")
            if bound_ports:
                first = bound_ports[0]
                where = (f"{first} .. {first + networks - 1}" if self.bind_port else
                         f"{first} (network 0; each network's port chosen by the OS)")
                urls.append(f"MAVProxy:       --master=udpout:127.0.0.1:{where}")
            return urls
        if self.api_port:
            if self.per_vehicle:
                urls.append(f"udpin://0.0.0.0:{self.api_port} .. "
                            f"{self.api_port + vehicles - 1} (one per vehicle)")
            else:
                urls.append(f"MAVSDK:         udpin://0.0.0.0:{self.api_port}")
        if self.gcs_port:
            urls.append(f"QGroundControl: UDP {self.gcs_port} (default link)")
        if bound_ports and not self.per_vehicle:
            urls.append(f"MAVProxy:       --master=udpout:127.0.0.1:{bound_ports[0]}")
        return urls
