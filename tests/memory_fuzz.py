"""A fuzz storm on a swarm's MAVLink network in memory, then proof that every vehicle still
answers and flies (used by tests/test_protocol_memory.py and perf/protocol_fuzz.py).

The storm feeds datagrams of tests/frame_fuzz.py straight into the network's
`receive_datagram`, takes what the swarm answers (undecoded), and runs one 20 ms turn of the
swarm (physics, telemetry, link timers) every `turn_every` datagrams. Afterwards each vehicle
is put back in order only as a ground station could (every parameter back by PARAM_SET, land,
disarm, HOLD), must answer a parameter read and an unknown command, and must arm, take off and
fly one 15 m hop by DO_REPOSITION, all checked against the ground truth.
"""

from __future__ import annotations

import math
import struct
import time
from collections.abc import Mapping
from dataclasses import dataclass

from emulator.flight.modes import FlightMode
from emulator.flight.params import ParamStore
from mavlink_vocabulary import (
    MavCmd,
    MavComponent,
    MavFrame,
    MavMissionType,
    MavParamType,
    MavResult,
)
from tests.frame_fuzz import FrameFuzzer
from tests.memory_link import MemoryLink

__all__ = ["HOP_M", "StormResult", "recover_and_fly", "storm"]

HOP_M = 15.0
FUZZER = ("10.0.0.9", 14550)  # where the storm comes from
UNKNOWN_COMMAND = 31999
PX4_AUTO, PX4_LOITER = 4, 3  # DO_SET_MODE custom mode AUTO, sub mode LOITER (HOLD)


@dataclass(frozen=True, slots=True)
class StormResult:
    frames: int
    datagrams: int
    frames_ok: int
    frames_bad: int
    replies: int  # datagrams the swarm sent back
    wall_s: float
    sim_s: float

    def line(self) -> str:
        rate = self.frames / self.wall_s if self.wall_s > 0 else math.inf
        return (f"{self.frames} frames in {self.datagrams} datagrams, {self.wall_s:.1f} s "
                f"({rate:,.0f} frames/s); decoded ok {self.frames_ok}, bad {self.frames_bad}; "
                f"{self.replies} datagrams answered; {self.sim_s:.1f} s simulated")


def storm(link: MemoryLink, fuzzer: FrameFuzzer, frames: int, *, per_datagram: int = 8,
          turn_every: int = 250) -> StormResult:
    """Feed `frames` fuzz frames to the network (see the module docstring)."""
    network, decoder = link.network, link.network.decoder
    ok0, bad0, sim0 = decoder.frames_ok, decoder.frames_bad, link.fleet.now_s
    sent = datagrams = replies = 0
    start = time.perf_counter()
    while sent < frames:
        count = min(per_datagram, frames - sent)
        network.receive_datagram(fuzzer.datagram(count), FUZZER, link.now)
        replies += sum(addr == FUZZER for _, addr in network.datagrams_to_send(link.now))
        sent += count
        datagrams += 1
        if datagrams % turn_every == 0:
            link.turn(decode=False)
    wall = time.perf_counter() - start
    return StormResult(sent, datagrams, decoder.frames_ok - ok0, decoder.frames_bad - bad0,
                       replies, wall, link.fleet.now_s - sim0)


def _run_until(link: MemoryLink, done, sim_s: float, what: str) -> None:
    t0 = link.fleet.now_s
    while not done():
        if link.fleet.now_s - t0 > sim_s:
            raise AssertionError(f"{what}: not within {sim_s:.0f} s of simulated time")
        link.turn(decode=False)


def _param_set(link: MemoryLink, system: int, name: str, value: float) -> None:
    if ParamStore.definition(name).is_int:
        wire = struct.unpack("<f", struct.pack("<i", int(value)))[0]
        kind = MavParamType.INT32
    else:
        wire, kind = value, MavParamType.REAL32
    since = link.send(link.mav.param_set_encode(system, MavComponent.AUTOPILOT1, name.encode(),
                                                wire, kind))
    echo = link.wait_for("PARAM_VALUE", system=system, since=since, within_s=0.0,
                         where=lambda m: m.param_id == name)
    assert echo.param_value == _float32(wire), (system, name, echo.to_dict())


def _float32(value: float) -> float:
    return struct.unpack("<f", struct.pack("<f", value))[0]


def _hop(link: MemoryLink, system: int) -> tuple[float, float]:
    """HOP_M from where the vehicle is, towards home if the way is clear (else the first
    clear one of eight directions)."""
    ap = link.fleet.autopilots[system - 1]
    x, y, z = ap.position_m
    heading = math.atan2(ap.home_m[1] - y, ap.home_m[0] - x)
    for turn in range(8):
        angle = heading + turn * math.pi / 4.0
        target = (x + HOP_M * math.cos(angle), y + HOP_M * math.sin(angle))
        if link.fleet.world.first_blockage((x, y, z), (*target, z)) is None:
            return target
    raise AssertionError(f"vehicle {system} is boxed in by obstacles at {(x, y, z)}")


def recover_and_fly(link: MemoryLink, system: int, params_at_start: Mapping[str, float]) -> None:
    """The vehicle answers; put back in order, it takes off and flies one hop."""
    ap = link.fleet.autopilots[system - 1]
    link.collect()  # from here on the client reads what comes back
    since = link.send(link.mav.param_request_read_encode(
        system, MavComponent.AUTOPILOT1, b"MPC_XY_VEL_MAX", -1))
    assert link.wait_for("PARAM_VALUE", system=system, since=since, within_s=0.0
                         ).param_id == "MPC_XY_VEL_MAX"
    assert link.command_long(system, UNKNOWN_COMMAND).result == MavResult.UNSUPPORTED
    for name, value in params_at_start.items():
        if _float32(ap.params[name]) != _float32(value):
            _param_set(link, system, name, value)
    # the plans cleared (a fuzzed fence may enclose nothing), as a ground station would
    since = link.send(link.mav.mission_clear_all_encode(system, MavComponent.AUTOPILOT1,
                                                        MavMissionType.ALL))
    assert link.wait_for("MISSION_ACK", system=system, since=since, within_s=0.0,
                         where=lambda m: m.mission_type == MavMissionType.ALL).type == 0
    if ap.in_air:
        assert link.command_long(system, MavCmd.NAV_LAND, *[math.nan] * 7).result == 0
        _run_until(link, lambda: not ap.in_air, 60.0 + 2.0 * max(ap.position_m[2], 0.0),
                   f"vehicle {system} landing")
    if ap.armed:
        assert link.command_long(system, MavCmd.COMPONENT_ARM_DISARM, 0.0).result == 0
    ack = link.command_long(system, MavCmd.DO_SET_MODE, 1, PX4_AUTO, PX4_LOITER)
    assert ack.result == MavResult.ACCEPTED and ap.mode is FlightMode.HOLD, ack.to_dict()

    vid = ap.vehicle_id
    t0 = link.fleet.now_s
    assert link.command_long(system, MavCmd.COMPONENT_ARM_DISARM, 1.0).result == 0
    ack = link.command_long(system, MavCmd.NAV_TAKEOFF, *[math.nan] * 7)
    assert ack.result == MavResult.ACCEPTED, (system, ack.to_dict())
    _run_until(link, lambda: bool(link.swarm.recorder.events(
        vid, t0_s=t0, kinds=("takeoff_complete",))), 60.0, f"vehicle {system} take-off")
    x, y = _hop(link, system)
    lat, lon, _ = link.fleet.world.origin.to_geodetic(x, y, 0.0)
    since = link.send(link.mav.command_int_encode(
        system, MavComponent.AUTOPILOT1, MavFrame.GLOBAL, MavCmd.DO_REPOSITION, 0, 0,
        math.nan, 1.0, 0.0, math.nan, round(lat * 1e7), round(lon * 1e7), math.nan))
    ack = link.wait_for("COMMAND_ACK", system=system, since=since, within_s=0.0)
    assert ack.result == MavResult.ACCEPTED, (system, ack.to_dict())

    def arrived() -> bool:
        px, py, _ = ap.position_m
        return math.hypot(px - x, py - y) < 0.5 and link.fleet.dyn.speed_m_s(ap.k) < 0.3

    _run_until(link, arrived, 30.0 + 2.0 * HOP_M, f"vehicle {system} hop")
