"""Batched telemetry is byte-identical to pymavlink, message by message.

Three levels: the framer (random field values over each field's whole range, edge values
and zero tails included, several message types and senders in one batch, sequence numbers
wrapping); the fleet builders (random vehicle states against `emulator.mavlink.messages`
packed by the vehicle's own encoder, sequences shared); and a running swarm seen by a raw
pymavlink ground station (every frame valid, one unbroken sequence per vehicle/component
across telemetry and replies), also with one port per vehicle.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import math
import random
import socket

import numpy as np
import pytest

from emulator.clock import ClockConfig
from emulator.flight.autopilot_mission import MissionState
from emulator.flight.battery import BATTERY_CRITICAL, BATTERY_EMERGENCY
from emulator.flight.fleet import Fleet
from emulator.flight.modes import FlightMode, LandedState
from emulator.mavlink.codec import Encoder, mavlink
from emulator.mavlink.frames import FramePart, MessageLayout, frame_batch, x25_crc
from emulator.mavlink.streams import DEFAULT_STREAMS, StreamSchedule
from emulator.mavlink.telemetry import _LAYOUTS, BATCHED_STREAMS, FleetTelemetry
from emulator.mavlink.vehicle_link import VehicleLink
from emulator.scenario import default_scenario
from emulator.swarm import PortPlan, Swarm
from tests.mavlink_client import running_swarm

LAYOUTS = sorted({id(v): v for v in _LAYOUTS.values()}.values(), key=lambda x: x.msg_id)


def test_every_default_stream_is_batched() -> None:
    assert {s.msg_id for s in DEFAULT_STREAMS} <= BATCHED_STREAMS


def test_crc_matches_pymavlink() -> None:
    rng = np.random.default_rng(7)
    for size in (0, 1, 2, 3, 17, 64, 255):
        data = rng.integers(0, 256, size, dtype=np.uint8).tobytes()
        assert x25_crc(data) == mavlink.x25crc(data).crc


def _random_field(rng: np.random.Generator, kind: np.dtype, n: int) -> np.ndarray:
    """n values of a numeric field: about a third edge values (0, min, max, ±1)."""
    if kind.kind == "f":
        values = rng.normal(0.0, 10.0 ** rng.integers(-3, 8, n), n)
        edges = np.array([0.0, -0.0, 1.0, -1.0, 3.4e38, -3.4e38, 1e-40, math.nan, math.inf,
                          -math.inf, 0.1, 12.5])
    else:
        info = np.iinfo(kind)
        values = rng.integers(info.min, info.max, n, endpoint=True, dtype=kind.newbyteorder("="))
        edges = np.array([0, info.min, info.max, 1, info.max - 1], dtype=object)
    pick = rng.random(n) < 0.35
    values = values.astype(object)
    values[pick] = rng.choice(edges, int(pick.sum()))
    values[rng.random(n) < 0.2] = 0  # zero fields, many at the tail
    return values


def _random_values(rng: np.random.Generator, layout: MessageLayout, n: int) -> list[list]:
    """Per row, constructor arguments in pymavlink's order."""
    cls = mavlink.mavlink_map[layout.msg_id]
    columns = []
    for name in cls.fieldnames:
        kind = layout.dtype.fields[name][0]
        if kind.subdtype is not None:
            base, shape = kind.subdtype
            cols = [_random_field(rng, base, n) for _ in range(shape[0])]
            columns.append([[c[i] for c in cols] for i in range(n)])
        else:
            columns.append(list(_random_field(rng, kind, n)))
    rows = [[col[i] for col in columns] for i in range(n)]
    for row in rows[: n // 4]:  # whole tails of zeros: truncation down to one byte
        for j in range(rng.integers(0, len(row)), len(row)):
            row[j] = [0] * len(row[j]) if isinstance(row[j], list) else 0
    return rows


def _py(value):
    if isinstance(value, list):
        return [_py(v) for v in value]
    return float(value) if isinstance(value, float | np.floating) else int(value)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_frames_match_pymavlink_for_random_fields(seed: int) -> None:
    rng = np.random.default_rng(seed)
    encoders: dict[tuple[int, int], Encoder] = {}
    expected: list[bytes] = []
    parts = []
    for layout in LAYOUTS:
        n = 40
        rows = _random_values(rng, layout, n)
        systems = rng.choice(np.arange(1, 256), n, replace=False)
        component = int(rng.choice([1, 100, 0, 255]))
        seqs = np.empty(n, dtype=np.uint8)
        for i, row in enumerate(rows):
            enc = encoders.setdefault((int(systems[i]), component),
                                      Encoder(int(systems[i]), component))
            enc._mav.seq = int(rng.choice([0, 254, 255, rng.integers(256)]))
            seqs[i] = enc._mav.seq
            cls = mavlink.mavlink_map[layout.msg_id]
            expected.append(enc.pack(cls(*[_py(v) for v in row])))
        records = np.zeros(n, dtype=layout.dtype)
        for j, name in enumerate(layout.fieldnames):
            kind = layout.dtype.fields[name][0]
            base = kind.subdtype[0] if kind.subdtype is not None else kind
            records[name] = np.array([_py(r[j]) for r in rows], dtype=base)
        parts.append(FramePart(layout, records, systems, component, seqs))
    frames = frame_batch(parts)
    got = [frames.frame(i) for i in range(len(frames))]
    assert len(got) == len(expected)
    for i, (a, b) in enumerate(zip(got, expected, strict=True)):
        assert a == b, f"frame {i}: batched {a.hex()} != pymavlink {b.hex()}"
    assert frames.data == b"".join(expected)


def _randomise(fleet: Fleet, rng: np.random.Generator) -> None:
    n = fleet.n
    dyn, bat = fleet.dyn, fleet.bat
    dyn.position_m = rng.normal(0.0, 1.0, (n, 3)) * rng.choice([0.0, 1.0, 300.0, 40_000.0],
                                                               (n, 3))
    dyn.velocity_m_s = rng.normal(0.0, 8.0, (n, 3))
    dyn.velocity_m_s[::5] = 0.0
    dyn.velocity_m_s[1::7] = [0.125, -0.125, 0.005]  # exact halves of a cm/s: even rounding
    dyn.velocity_m_s[2::7] = [0.05, 0.07, -300.0]
    dyn.accel_m_s2 = rng.normal(0.0, 3.0, (n, 3))
    dyn.accel_m_s2[::6] = 0.0
    dyn.yaw_deg = rng.uniform(0.0, 360.0, n)
    dyn.yaw_deg[:6] = [0.0, 359.999999, 180.0, 90.0, 0.005, 359.995]
    bat.pct = rng.uniform(0.0, 100.0, n)
    bat.pct[:4] = [0.0, 100.0, 50.0, 6.0]
    bat.level = rng.integers(0, 4, n).astype(np.int8)
    bat.level[:4] = [BATTERY_EMERGENCY, 0, BATTERY_CRITICAL, BATTERY_CRITICAL]
    bat.charge_rate_pct_s = np.where(rng.random(n) < 0.3, 0.5, 0.0)
    bat.hover_endurance_s = rng.uniform(60.0, 3000.0, n)
    fleet.armed[:] = rng.random(n) < 0.5
    fleet.airborne[:] = fleet.armed & (rng.random(n) < 0.7)
    fleet.step_count = int(rng.integers(0, 2**31))
    modes, landed = list(FlightMode), list(LandedState)
    for ap in fleet.autopilots:
        ap.mode = modes[rng.integers(len(modes))]
        ap.landed_state = landed[rng.integers(len(landed))]
        ap.home_m = tuple(rng.normal(0.0, 500.0, 3).tolist())
        ap.params._values["BAT_V_EMPTY"] = float(rng.uniform(3.0, 3.6))
        ap.params._values["BAT_V_CHARGED"] = float(rng.uniform(4.0, 4.35))
        ap.params._values["BAT_N_CELLS"] = float(rng.integers(1, 13))
        ap.params._values["BAT_CAPACITY"] = float(rng.uniform(100.0, 30000.0))
        ap.mission.current = int(rng.integers(0, 1000))
        ap.mission.state = int(rng.choice([MissionState.NO_MISSION, 2, 3, 4, 5]))


@pytest.mark.parametrize("seed", [11, 12])
def test_fleet_telemetry_matches_the_message_builders(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 60
    fleet = Fleet(default_scenario(n))
    _randomise(fleet, rng)
    sent: list[tuple[int, bytes]] = []
    schedule = StreamSchedule(n, 0.0)
    links = [VehicleLink(ap, lambda k, data: sent.append((k, data)), schedule, lambda: 0.0)
             for ap in fleet.autopilots]
    telemetry = FleetTelemetry(fleet)
    for link in links:
        for component, seqs in telemetry.sequences.items():
            link.encoder(component).share_sequence(seqs, link.k)
    telemetry.sequences[1][:] = rng.integers(0, 256, n)
    telemetry.sequences[1][:3] = 255
    for round_ in range(3):
        if round_ == 2:  # new headings and accelerations: nothing from the rounds before
            _randomise(fleet, rng)
        for msg_id in sorted(BATCHED_STREAMS):
            ks = np.sort(rng.choice(n, int(rng.integers(1, n + 1)), replace=False))
            before = {c: s.copy() for c, s in telemetry.sequences.items()}
            frames = frame_batch([telemetry.part(msg_id, ks)])
            after = {c: s.copy() for c, s in telemetry.sequences.items()}
            for c, s in before.items():
                telemetry.sequences[c][:] = s
            sent.clear()
            for k in ks.tolist():
                links[k].send_stream(msg_id)
            assert [k for k, _ in sent] == ks.tolist()
            for i, (k, data) in enumerate(sent):
                assert frames.frame(i) == data, (
                    f"message {msg_id}, vehicle {k}: batched {frames.frame(i).hex()} != "
                    f"pymavlink {data.hex()}")
            for c in before:
                assert np.array_equal(telemetry.sequences[c], after[c])


async def test_swarm_frames_are_valid_with_one_sequence_per_component() -> None:
    async with running_swarm(3, speed=5.0) as (swarm, client):
        for _ in range(10):  # replies interleave with the batched telemetry
            client.send(mavlink.MAVLink_param_request_read_message(2, 1, b"", 0))
            await asyncio.sleep(0.12)
        swarm.send_all_telemetry()  # a burst: every stream of every vehicle at once
        await asyncio.sleep(0.3)
        assert client.bad_in == 0
        by_sender: dict[tuple[int, int], list[int]] = {}
        types: dict[int, set[str]] = {}
        for r in client.received:
            m = r.msg
            by_sender.setdefault((m.get_srcSystem(), m.get_srcComponent()), []).append(
                m.get_seq())
            types.setdefault(m.get_srcSystem(), set()).add(m.get_type())
        assert set(by_sender) == {(s, c) for s in (1, 2, 3) for c in (1, 100)}
        for sender, seqs in by_sender.items():
            steps = {(b - a) % 256 for a, b in itertools.pairwise(seqs)}
            assert steps == {1}, f"{sender}: sequence not consecutive: {seqs}"
        names = {s.name for s in DEFAULT_STREAMS if s.msg_id >= 0 and s.default_hz > 0}
        for system in (1, 2, 3):
            assert names <= types[system], f"{system}: missing {names - types[system]}"
        assert "PARAM_VALUE" in types[2]


def _consecutive_udp_sockets(count: int) -> list[socket.socket]:
    """`count` bound sockets on consecutive loopback ports (retrying taken ranges), below
    Linux's ephemeral range (32768 and up), where tests/ports.py hands ports out."""
    rng = random.Random()
    for _ in range(50):
        base = rng.randrange(20_000, 32_000)
        socks: list[socket.socket] = []
        try:
            for i in range(count):
                s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
                socks.append(s)
                s.bind(("127.0.0.1", base + i))
                s.setblocking(False)
            return socks
        except OSError:
            for s in socks:
                s.close()
    raise RuntimeError("no free range of UDP ports")


async def test_per_vehicle_ports_get_only_their_vehicles_batched_frames() -> None:
    n = 3
    receivers = _consecutive_udp_sockets(n)
    try:
        for _ in range(20):
            base = random.randrange(20_000, 60_000)
            ports = PortPlan(bind_host="127.0.0.1", bind_port=base, api_port=receivers[0]
                             .getsockname()[1], gcs_port=0, per_vehicle=True)
            swarm = Swarm(default_scenario(n), clock=ClockConfig(speed=5.0), ports=ports)
            try:
                await swarm.start()
                break
            except OSError:
                continue
        else:
            pytest.fail("no free range of UDP ports for the swarm")
        try:
            await asyncio.sleep(1.5)
        finally:
            await swarm.close()
        for k, sock in enumerate(receivers):
            parser = mavlink.MAVLink(None)
            got: list = []
            with contextlib.suppress(BlockingIOError):
                while True:
                    got += parser.parse_buffer(sock.recv(65535)) or []
            assert got, f"vehicle {k + 1}'s port received nothing"
            assert {m.get_srcSystem() for m in got} == {k + 1}
            assert all(m.get_msgId() >= 0 for m in got)
            assert {"HEARTBEAT", "GLOBAL_POSITION_INT", "ATTITUDE"} <= {m.get_type() for m in got}
    finally:
        for sock in receivers:
            sock.close()
