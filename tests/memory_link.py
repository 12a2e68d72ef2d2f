"""A ground station and a swarm's MAVLink network paired in memory: no socket, no event loop.

`MemoryLink` builds a real `Swarm` (not started: no socket is opened) and talks to its
`NetworkProtocol` (emulator.mavlink.protocol) directly: it encodes frames with pymavlink
(system 255 / component 190, as QGroundControl), feeds them with `receive_datagram`,
collects the swarm's answers with `datagrams_to_send` and decodes them. Time is the test's:
`advance` moves the wall clock the network sees and runs the fleet's physics by the same
simulated time (a stepped clock at 1x), sending the telemetry due and the links' timers on
the way. Everything runs as fast as the machine allows and is deterministic.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from pymavlink.dialects.v20 import common as mavlink

from emulator.clock import ClockConfig
from emulator.link_faults import LinkFaults
from emulator.mavlink.protocol import NetworkProtocol
from emulator.scenario import Scenario, default_scenario
from emulator.swarm import PortPlan, Swarm
from mavlink_vocabulary import (
    MavAutopilot,
    MavCmd,
    MavComponent,
    MavFrame,
    MavMissionType,
    MavState,
    MavType,
)

__all__ = ["CLIENT", "GCS_COMPONENT", "GCS_SYSTEM", "MemoryLink", "mavlink"]

GCS_SYSTEM = 255
GCS_COMPONENT = MavComponent.MISSIONPLANNER
CLIENT = ("10.0.0.2", 14550)  # the client's address as the network sees it
TICK_S = 0.02  # wall (and simulated) seconds per turn of `advance`
START_S = 1000.0  # the memory wall clock's start
Match = Callable[[mavlink.MAVLink_message], bool]


@dataclass(frozen=True, slots=True)
class Received:
    t: float  # the memory wall clock at arrival
    msg: mavlink.MAVLink_message


class MemoryLink:
    """A client of one swarm network, in memory (see the module docstring)."""

    def __init__(self, n: int = 3, *, scenario: Scenario | None = None,
                 telemetry: bool = True, link_faults: LinkFaults | None = None) -> None:
        self.swarm = Swarm(scenario or default_scenario(n), clock=ClockConfig(stepped=True),
                           ports=PortPlan(api_port=0, gcs_port=0), link_faults=link_faults)
        self.now = START_S
        self.swarm.streams.next_due_s += START_S - self.swarm.streams.next_wakeup_s()
        self.network: NetworkProtocol = self.swarm.networks[0]
        self.network.open()
        self.telemetry = telemetry
        self.mav = mavlink.MAVLink(None, srcSystem=GCS_SYSTEM, srcComponent=GCS_COMPONENT)
        self._parser = mavlink.MAVLink(None, srcSystem=0, srcComponent=0)
        self._parser.robust_parsing = True
        self.received: list[Received] = []
        self.datagrams_in = 0
        self.bad_in = 0
        self.send(self.mav.heartbeat_encode(MavType.GCS, MavAutopilot.INVALID, 0, 0,
                                            MavState.ACTIVE, 3))

    @property
    def fleet(self):
        return self.swarm.fleet

    # ------------------------------------------------------------------- wire
    def pack(self, msg: mavlink.MAVLink_message) -> bytes:
        data = msg.pack(self.mav)
        self.mav.seq = (self.mav.seq + 1) & 0xFF
        return data

    def send(self, msg: mavlink.MAVLink_message) -> int:
        """Send one message; returns the index in `received` from which its answers count."""
        return self.send_raw(self.pack(msg))

    def send_raw(self, data: bytes) -> int:
        mark = len(self.received)
        self.network.receive_datagram(data, CLIENT, self.now)
        self.collect()
        return mark

    def collect(self, *, decode: bool = True) -> int:
        """Take what the network has to send; decode what is for this client. Returns the
        number of datagrams taken."""
        out = self.network.datagrams_to_send(self.now)
        for data, addr in out:
            if addr != CLIENT:
                continue
            self.datagrams_in += 1
            if not decode:
                continue
            parser = self._parser
            try:
                msgs = parser.parse_buffer(data) or []
            except mavlink.MAVError:
                self.bad_in += 1
                msgs = []
            finally:
                parser.buf = bytearray()
                parser.buf_index = 0
                parser.expected_length = mavlink.HEADER_LEN_V1 + 2
            for m in msgs:
                if m.get_msgId() < 0:
                    self.bad_in += 1
                else:
                    self.received.append(Received(self.now, m))
        return len(out)

    # ------------------------------------------------------------------- time
    def turn(self, dt_s: float = TICK_S, *, decode: bool = True) -> None:
        """One turn of the swarm's duties: `dt_s` of wall and simulated time, the physics,
        fault events, link timers and the telemetry due."""
        swarm = self.swarm
        self.now += dt_s
        steps = max(1, round(dt_s / swarm.fleet.dt_s))
        swarm.fleet.run(steps)
        swarm.faults.fire_due()
        swarm.tick_links(self.now)
        if self.telemetry:
            swarm.send_due_telemetry(self.now)
        self.collect(decode=decode)

    def advance(self, seconds: float) -> None:
        for _ in range(max(1, math.ceil(seconds / TICK_S - 1e-9))):
            self.turn()

    # ------------------------------------------------------------------ query
    def messages(self, mtype: str | Iterable[str] | None = None, *, system: int | None = None,
                 where: Match | None = None, since: int = 0) -> list[mavlink.MAVLink_message]:
        kinds = None if mtype is None else (mtype,) if isinstance(mtype, str) else tuple(mtype)
        return [r.msg for r in self.received[since:]
                if (kinds is None or r.msg.get_type() in kinds)
                and (system is None or r.msg.get_srcSystem() == system)
                and (where is None or where(r.msg))]

    def wait_for(self, mtype: str | Iterable[str] | None = None, *, system: int | None = None,
                 where: Match | None = None, since: int = 0,
                 within_s: float = 5.0) -> mavlink.MAVLink_message:
        """The first matching message after `since`, advancing time up to `within_s`."""
        deadline = self.now + within_s
        while True:
            found = self.messages(mtype, system=system, where=where, since=since)
            if found:
                return found[0]
            if self.now >= deadline:
                raise TimeoutError(f"no {mtype or 'message'} from system {system} "
                                   f"within {within_s} s")
            self.turn()

    # --------------------------------------------------------------- commands
    def command_long(self, system: int, command: int, *params: float,
                     component: int = MavComponent.AUTOPILOT1) -> mavlink.MAVLink_message:
        """Send a COMMAND_LONG; its COMMAND_ACK (answers come at once, in memory)."""
        p = [*params, *([0.0] * (7 - len(params)))]
        since = self.send(self.mav.command_long_encode(system, component, command, 0, *p))
        return self.wait_for("COMMAND_ACK", system=system, since=since, within_s=0.0,
                             where=lambda m: m.command == command)

    def mission_item(self, system: int, seq: int, command: int, lat_deg: float, lon_deg: float,
                     alt_m: float, *, frame: int = MavFrame.GLOBAL_RELATIVE_ALT_INT,
                     params: tuple[float, float, float, float] = (0.0, 0.0, 0.0, math.nan)
                     ) -> mavlink.MAVLink_message:
        return self.mav.mission_item_int_encode(
            system, MavComponent.AUTOPILOT1, seq, frame, command, int(seq == 0), 1, *params,
            round(lat_deg * 1e7), round(lon_deg * 1e7), alt_m, MavMissionType.MISSION)

    def upload_mission(self, system: int, items: list[mavlink.MAVLink_message]
                       ) -> mavlink.MAVLink_message:
        """The mission protocol from the ground station's side: COUNT, then each requested
        item, until the vehicle's MISSION_ACK (returned)."""
        since = self.send(self.mav.mission_count_encode(
            system, MavComponent.AUTOPILOT1, len(items), MavMissionType.MISSION))
        while True:
            m = self.wait_for(("MISSION_REQUEST_INT", "MISSION_ACK"), system=system,
                              since=since, within_s=1.0)
            if m.get_type() == "MISSION_ACK":
                return m
            since = self.send(items[m.seq])

    def download_mission(self, system: int) -> list[mavlink.MAVLink_message]:
        since = self.send(self.mav.mission_request_list_encode(
            system, MavComponent.AUTOPILOT1, MavMissionType.MISSION))
        count = self.wait_for("MISSION_COUNT", system=system, since=since, within_s=0.0).count
        items = []
        for seq in range(count):
            since = self.send(self.mav.mission_request_int_encode(
                system, MavComponent.AUTOPILOT1, seq, MavMissionType.MISSION))
            items.append(self.wait_for("MISSION_ITEM_INT", system=system, since=since,
                                       within_s=0.0))
        return items

    def arm_and_take_off(self, system: int, altitude_m: float = 10.0) -> None:
        """Arm, take off (to the takeoff altitude parameter) and wait until airborne."""
        ap = self.fleet.autopilots[system - 1]
        ap.set_param("MIS_TAKEOFF_ALT", altitude_m)
        assert self.command_long(system, MavCmd.COMPONENT_ARM_DISARM, 1.0).result == 0
        assert self.command_long(system, MavCmd.NAV_TAKEOFF, *([math.nan] * 7)).result == 0
        self.wait_for("EXTENDED_SYS_STATE", system=system, since=len(self.received),
                      within_s=60.0, where=lambda m: m.landed_state == 2)  # in the air
