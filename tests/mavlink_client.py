"""A raw pymavlink ground station over a real UDP socket, for protocol-level tests.

No mocks: the client owns an asyncio datagram socket on 127.0.0.1, encodes with
``pymavlink.dialects.v20.common.MAVLink`` (system 255 / component 190, as QGroundControl)
and decodes whatever comes back with ``parse_buffer``. Every message received is kept, in
order, with its wall-clock arrival time, so a test can wait for a reply that matches a
predicate, count a stream's rate, or check that something did NOT arrive.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import socket
import time
from collections.abc import AsyncIterator, Callable, Iterable
from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink

from emulator.clock import ClockConfig
from emulator.scenario import Scenario, default_scenario
from emulator.swarm import PortPlan, Swarm

__all__ = [
    "GCS_COMPONENT",
    "GCS_SYSTEM",
    "LoopErrors",
    "MavClient",
    "Received",
    "mavlink",
    "running_swarm",
    "scheduler_alive",
    "swarm_socket_open",
]

GCS_SYSTEM = 255
GCS_COMPONENT = 190
Address = tuple[str, int]
Match = Callable[[mavlink.MAVLink_message], bool]


@dataclass(frozen=True, slots=True)
class Received:
    t: float  # time.monotonic() at arrival
    msg: mavlink.MAVLink_message


class MavClient(asyncio.DatagramProtocol):
    """A ground station talking to one swarm socket.

    ``send`` remembers how many messages had arrived, and ``wait_for`` by default only
    looks at messages received after the last send: a reply can never be confused with an
    older message of the same type.
    """

    def __init__(self, remote: Address, *, system: int = GCS_SYSTEM,
                 component: int = GCS_COMPONENT) -> None:
        self.remote = remote
        self.mav = mavlink.MAVLink(None, srcSystem=system, srcComponent=component)
        self._parser = mavlink.MAVLink(None, srcSystem=0, srcComponent=0)
        self._parser.robust_parsing = True
        self.received: list[Received] = []
        self.datagrams_in = 0
        self.bad_in = 0
        self.mark = 0
        self.transport: asyncio.DatagramTransport | None = None
        self._arrived = asyncio.Event()
        self.paused = False  # when True, incoming datagrams are dropped unread
        self.drop: Match | None = None  # messages it matches are discarded (simulated loss)
        self.loop_errors: LoopErrors | None = None  # set by running_swarm

    # ------------------------------------------------------------- lifecycle
    @classmethod
    async def connect(cls, remote: Address, **kwargs: int) -> MavClient:
        loop = asyncio.get_running_loop()
        client = cls(remote, **kwargs)
        transport, _ = await loop.create_datagram_endpoint(lambda: client,
                                                           local_addr=("127.0.0.1", 0))
        sock = transport.get_extra_info("socket")
        with contextlib.suppress(OSError):  # room for bursts (capped by net.core.rmem_max)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)
        return client

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = transport  # type: ignore[assignment]

    def error_received(self, exc: Exception) -> None:  # ICMP from a closed port: ignore
        pass

    def close(self) -> None:
        if self.transport is not None:
            self.transport.close()
            self.transport = None

    @property
    def local_address(self) -> Address:
        assert self.transport is not None
        return self.transport.get_extra_info("sockname")[:2]

    # --------------------------------------------------------------- receive
    def datagram_received(self, data: bytes, addr: Address) -> None:
        if self.paused:
            return
        self.datagrams_in += 1
        now = time.monotonic()
        try:
            msgs = self._parser.parse_buffer(data) or []
        except mavlink.MAVError:
            self.bad_in += 1
            msgs = []
        finally:
            self._parser.buf = bytearray()
            self._parser.buf_index = 0
            self._parser.expected_length = mavlink.HEADER_LEN_V1 + 2
        drop = self.drop
        for m in msgs:
            if m.get_msgId() < 0:
                self.bad_in += 1
            elif drop is None or not drop(m):
                self.received.append(Received(now, m))
        self._arrived.set()

    # ------------------------------------------------------------------ send
    def send(self, msg: mavlink.MAVLink_message) -> bytes:
        """Pack and send one message; later ``wait_for`` calls look only after this point."""
        data = msg.pack(self.mav)
        self.mav.seq = (self.mav.seq + 1) & 0xFF
        self.mark = len(self.received)
        self.send_raw(data)
        return data

    def send_raw(self, data: bytes) -> None:
        assert self.transport is not None, "client is closed"
        if data:
            self.transport.sendto(data, self.remote)
        else:  # asyncio's sendto silently skips empty datagrams: use a plain socket
            with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
                sock.sendto(data, self.remote)

    def pack(self, msg: mavlink.MAVLink_message) -> bytes:
        """Bytes of one frame as this client would send it (advances the sequence)."""
        data = msg.pack(self.mav)
        self.mav.seq = (self.mav.seq + 1) & 0xFF
        return data

    # ----------------------------------------------------------------- query
    @staticmethod
    def _matches(m: mavlink.MAVLink_message, mtype: str | Iterable[str] | None,
                 system: int | None, component: int | None, where: Match | None) -> bool:
        if mtype is not None:
            kinds = (mtype,) if isinstance(mtype, str) else tuple(mtype)
            if m.get_type() not in kinds:
                return False
        if system is not None and m.get_srcSystem() != system:
            return False
        if component is not None and m.get_srcComponent() != component:
            return False
        return where is None or bool(where(m))

    def messages(self, mtype: str | Iterable[str] | None = None, *, system: int | None = None,
                 component: int | None = None, where: Match | None = None,
                 since: int = 0) -> list[mavlink.MAVLink_message]:
        return [r.msg for r in self.received[since:]
                if self._matches(r.msg, mtype, system, component, where)]

    def timed(self, mtype: str, *, system: int | None = None,
              since: int = 0) -> list[Received]:
        return [r for r in self.received[since:]
                if self._matches(r.msg, mtype, system, None, None)]

    async def wait_for(self, mtype: str | Iterable[str] | None = None, *,
                       system: int | None = None, component: int | None = None,
                       where: Match | None = None, timeout: float = 2.0,
                       since: int | None = None) -> mavlink.MAVLink_message:
        """The first matching message received after `since` (default: the last send)."""
        start = self.mark if since is None else since
        deadline = time.monotonic() + timeout
        index = start
        while True:
            while index < len(self.received):
                m = self.received[index].msg
                index += 1
                if self._matches(m, mtype, system, component, where):
                    return m
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(
                    f"no {mtype or 'message'} from system {system} within {timeout} s"
                )
            self._arrived.clear()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._arrived.wait(), timeout=left)

    async def wait_index(self, mtype: str | Iterable[str] | None = None, *,
                         system: int | None = None, where: Match | None = None,
                         timeout: float = 2.0, since: int | None = None) -> int:
        """Like ``wait_for`` but returns the index of the match in ``received``."""
        m = await self.wait_for(mtype, system=system, where=where, timeout=timeout, since=since)
        for i in range(len(self.received) - 1, -1, -1):
            if self.received[i].msg is m:
                return i
        raise AssertionError("unreachable")

    async def expect_none(self, mtype: str | Iterable[str], *, system: int | None = None,
                          where: Match | None = None, within: float = 0.5,
                          since: int | None = None) -> None:
        """Assert that no matching message arrives within `within` seconds."""
        start = self.mark if since is None else since
        await asyncio.sleep(within)
        got = self.messages(mtype, system=system, where=where, since=start)
        assert not got, f"unexpected {[m.to_dict() for m in got]}"

    async def settle(self, quiet_s: float = 0.3) -> None:
        await asyncio.sleep(quiet_s)

    # ------------------------------------------------------ protocol helpers
    async def command_long(self, system: int, command: int, *params: float,
                           component: int = 1, timeout: float = 2.0) -> mavlink.MAVLink_message:
        """Send COMMAND_LONG and return its COMMAND_ACK."""
        p = [*params] + [0.0] * (7 - len(params))
        self.send(self.mav.command_long_encode(system, component, command, 0, *p[:7]))
        return await self.wait_for(
            "COMMAND_ACK", system=system, where=lambda m: m.command == command, timeout=timeout
        )

    async def command_int(self, system: int, command: int, *, frame: int = 0,
                          p1: float = math.nan, p2: float = 0.0, p3: float = math.nan,
                          p4: float = math.nan, x: int = 0, y: int = 0, z: float = math.nan,
                          timeout: float = 2.0) -> mavlink.MAVLink_message:
        self.send(self.mav.command_int_encode(system, 1, frame, command, 0, 0,
                                              p1, p2, p3, p4, x, y, z))
        return await self.wait_for(
            "COMMAND_ACK", system=system, where=lambda m: m.command == command, timeout=timeout
        )

    async def param_set(self, system: int, name: str, value: float, ptype: int = 9,
                        timeout: float = 2.0) -> mavlink.MAVLink_message:
        self.send(self.mav.param_set_encode(system, 1, name.encode(), value, ptype))
        return await self.wait_for(
            "PARAM_VALUE", system=system, where=lambda m: m.param_id == name, timeout=timeout
        )

    async def param_read(self, system: int, name: str = "", index: int = -1,
                         timeout: float = 2.0) -> mavlink.MAVLink_message:
        self.send(self.mav.param_request_read_encode(system, 1, name.encode(), index))
        if index >= 0:
            return await self.wait_for("PARAM_VALUE", system=system,
                                       where=lambda m: m.param_index == index, timeout=timeout)
        return await self.wait_for("PARAM_VALUE", system=system,
                                   where=lambda m: m.param_id == name, timeout=timeout)

    async def upload_mission(self, system: int, items: list[mavlink.MAVLink_message],
                             timeout: float = 3.0) -> mavlink.MAVLink_message:
        """MAVSDK-style upload: COUNT, answer each MISSION_REQUEST_INT; returns MISSION_ACK."""
        start = len(self.received)
        self.send(self.mav.mission_count_encode(system, 1, len(items), 0))
        index = start
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("mission upload stalled")
            i = await self.wait_index(("MISSION_REQUEST_INT", "MISSION_ACK"), system=system,
                                      timeout=left, since=index)
            index = i + 1
            m = self.received[i].msg
            if m.get_type() == "MISSION_ACK":
                return m
            self.send_raw(self.pack(items[m.seq]))

    async def download_mission(self, system: int,
                               timeout: float = 2.0) -> list[mavlink.MAVLink_message]:
        self.send(self.mav.mission_request_list_encode(system, 1, 0))
        count = (await self.wait_for("MISSION_COUNT", system=system, timeout=timeout)).count
        items = []
        for seq in range(count):
            self.send(self.mav.mission_request_int_encode(system, 1, seq, 0))
            items.append(await self.wait_for("MISSION_ITEM_INT", system=system,
                                             where=lambda m, s=seq: m.seq == s, timeout=timeout))
        self.send(self.mav.mission_ack_encode(system, 1, 0, 0))
        return items

    def mission_item(self, system: int, seq: int, command: int, lat_deg: float = 0.0,
                     lon_deg: float = 0.0, alt_m: float = 0.0, *, frame: int = 6,
                     p1: float = 0.0, p2: float = 0.0, p3: float = 0.0,
                     p4: float = math.nan) -> mavlink.MAVLink_message:
        return self.mav.mission_item_int_encode(
            system, 1, seq, frame, command, 0, 1, p1, p2, p3, p4,
            round(lat_deg * 1e7), round(lon_deg * 1e7), alt_m, 0,
        )


class LoopErrors:
    """Collects whatever reaches the event loop's exception handler while installed.

    An exception raised while the swarm handles a datagram closes its socket (asyncio's
    "Fatal read error on datagram transport"), and one raised by the scheduler kills its task;
    both end up here or in ``scheduler_alive``.
    """

    def __init__(self) -> None:
        self.errors: list[dict] = []
        self._loop: asyncio.AbstractEventLoop | None = None
        self._previous = None

    def install(self) -> LoopErrors:
        self._loop = asyncio.get_running_loop()
        self._previous = self._loop.get_exception_handler()
        self._loop.set_exception_handler(lambda _loop, context: self.errors.append(context))
        return self

    def uninstall(self) -> None:
        if self._loop is not None:
            self._loop.set_exception_handler(self._previous)
            self._loop = None

    def describe(self) -> str:
        return "; ".join(f"{c.get('message')}: {c.get('exception')!r}" for c in self.errors)


async def send_datagram(sock: socket.socket, data: bytes, address: Address) -> None:
    """Send one datagram from a non-blocking socket, waiting while its buffer is full."""
    while True:
        try:
            sock.sendto(data, address)
            return
        except BlockingIOError:
            await asyncio.sleep(0.001)


def scheduler_alive(swarm: Swarm) -> bool:
    task = swarm._task
    return task is not None and not task.done()


def swarm_socket_open(swarm: Swarm) -> bool:
    return all(e.is_open for e in swarm.endpoints)


@contextlib.asynccontextmanager
async def running_swarm(n: int = 3, *, speed: float = 10.0, scenario: Scenario | None = None,
                        telemetry_hz: dict[str, float] | None = None,
                        ) -> AsyncIterator[tuple[Swarm, MavClient]]:
    """A swarm bound to an ephemeral port on 127.0.0.1 (no fixed destinations) and a client.

    The swarm answers the client because every peer that talks to it becomes a destination;
    the client announces itself with a GCS heartbeat.
    """
    ports = PortPlan(bind_host="127.0.0.1", bind_port=0, api_port=0, gcs_port=0)
    errors = LoopErrors().install()
    swarm = Swarm(scenario or default_scenario(n), clock=ClockConfig(speed=speed), ports=ports,
                  telemetry_hz=telemetry_hz)
    await swarm.start()
    client = None
    try:
        client = await MavClient.connect(swarm.endpoints[0].local_address)
        client.loop_errors = errors
        client.send(client.mav.heartbeat_encode(6, 8, 0, 0, 4, 3))
        await client.wait_for(system=1, timeout=3.0)  # any message: the swarm knows us
        yield swarm, client
        assert not errors.errors, f"event loop errors: {errors.describe()}"
        assert scheduler_alive(swarm), "the swarm's scheduler task died"
        assert swarm_socket_open(swarm), "the swarm's socket was closed"
        assert swarm.stats().internal_errors == 0, "a handler or telemetry builder raised"
    finally:
        errors.uninstall()
        if client is not None:
            client.close()
        await swarm.close()
