"""Discovery, health, telemetry and addressing: the swarm as MAVSDK sees it.

The real MAVSDK client (native binding) over UDP on 127.0.0.1, checked against the ground
truth."""

from __future__ import annotations

import asyncio
import math
from typing import Any

import pytest
from mavsdk.asyncio import Autopilot, Vehicle
from mavsdk.asyncio.plugins.action import ActionAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync
from mavsdk.plugins.telemetry import FlightMode
from pymavlink.dialects.v20 import common as mavlink

from tests.mavsdk_helpers import (
    CAMERA_COMPONENT_ID,
    eventually,
    first,
    geodetic,
    horizontal_error_m,
    kinds,
    take_off,
    truth_pos,
    watching,
)

pytestmark = pytest.mark.mavsdk


async def test_discovers_ten_vehicles(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(10)
    async with mavsdk_client(swarm.ports.api_port, 10) as systems:
        ids = [await s.get_system_id() for s in systems]
        assert ids == list(range(1, 11))
        for system in systems:
            assert await system.is_connected()
            assert await system.autopilot_type() == Autopilot.PX4
            assert await system.vehicle_type() == Vehicle.MULTICOPTER
            components = await system.component_ids()
            assert 1 in components and CAMERA_COMPONENT_ID in components
        # nothing was moved or armed by discovery alone
        for k in range(1, 11):
            assert not swarm.fleet.autopilots[k - 1].armed
            assert "arm" not in kinds(swarm, k)

async def test_health_all_ok_and_home_on_every_vehicle(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(10)
    async with mavsdk_client(swarm.ports.api_port, 10) as systems:
        telemetries = [TelemetryAsync(s) for s in systems]

        async def all_ok() -> bool:
            for tel in telemetries:
                h = await tel.health()
                if not (h.is_armable and h.is_global_position_ok and h.is_local_position_ok
                        and h.is_home_position_ok):
                    return False
            return True

        await eventually(all_ok, 5.0, "health all ok on 10 vehicles")
        for k, tel in enumerate(telemetries, start=1):
            assert await tel.health_all_ok()
            home = await first(tel.subscribe_home(), lambda h: math.isfinite(h.latitude_deg),
                               5.0, f"home of system {k}")
            hx, hy, hz = swarm.fleet.autopilots[k - 1].home_m
            assert horizontal_error_m(swarm, home.latitude_deg, home.longitude_deg, hx, hy) < 0.1
            assert home.absolute_altitude_m == pytest.approx(geodetic(swarm, hx, hy, hz)[2],
                                                             abs=0.05)

async def test_telemetry_streams_match_truth(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(3)
    async with mavsdk_client(swarm.ports.api_port, 3) as systems:
        sysid = 3  # home (10, 0)
        system = systems[sysid - 1]
        telemetry = TelemetryAsync(system)
        ap = swarm.fleet.autopilots[sysid - 1]
        hx, hy, hz = ap.home_m

        async with watching(
            telemetry.subscribe_position(), telemetry.subscribe_battery(),
            telemetry.subscribe_in_air(), telemetry.subscribe_flight_mode(),
            telemetry.subscribe_home(), telemetry.subscribe_armed(),
        ) as (position, battery, in_air, mode, home, armed):
            # on the ground, disarmed
            p = await position.wait(lambda p: True, 3.0, "position")
            assert horizontal_error_m(swarm, p.latitude_deg, p.longitude_deg, hx, hy) < 0.1
            assert p.relative_altitude_m == pytest.approx(0.0, abs=0.01)
            assert p.absolute_altitude_m == pytest.approx(geodetic(swarm, hx, hy, hz)[2],
                                                          abs=0.01)
            b = await battery.wait(lambda b: True, 3.0, "battery")
            assert b.remaining_percent == pytest.approx(ap.battery_pct, abs=1.0)
            n_cells = ap.params["BAT_N_CELLS"]
            assert 3.5 * n_cells <= b.voltage_v <= 4.2 * n_cells + 0.01
            assert await in_air.wait(lambda v: True, 3.0, "in_air") is False
            assert await armed.wait(lambda v: True, 3.0, "armed") is False
            assert await mode.wait(lambda v: True, 3.0, "flight mode") == FlightMode.HOLD
            h = await home.wait(lambda h: math.isfinite(h.latitude_deg), 3.0, "home")
            assert horizontal_error_m(swarm, h.latitude_deg, h.longitude_deg, hx, hy) < 0.1

            # in the air: every stream follows
            await take_off(swarm, system, sysid, 10.0)
            assert ap.in_air and ap.armed
            await armed.wait(lambda v: v, 3.0, "armed True")
            await in_air.wait(lambda v: v, 3.0, "in_air True")
            p = await position.wait(lambda p: abs(p.relative_altitude_m - 10.0) < 0.2, 3.0,
                                    "hovering at 10 m")
            x, y, z = truth_pos(swarm, sysid)
            assert horizontal_error_m(swarm, p.latitude_deg, p.longitude_deg, x, y) < 0.2
            assert p.absolute_altitude_m == pytest.approx(geodetic(swarm, x, y, z)[2], abs=0.2)
            # hovering drains the battery; telemetry reports the drained value
            start_pct = ap.battery_pct
            await eventually(lambda: ap.battery_pct < start_pct - 2.0, 10.0, "2 % drained")
            b = await battery.wait(lambda b: b.remaining_percent < start_pct - 1.0, 5.0,
                                   "battery telemetry drop")
            assert b.remaining_percent == pytest.approx(ap.battery_pct, abs=2.0)
            assert b.remaining_percent < 100.0
            # the home position stays where the vehicle took off
            h = home.values[-1]
            assert horizontal_error_m(swarm, h.latitude_deg, h.longitude_deg, hx, hy) < 0.1

async def test_command_to_unknown_system_is_ignored(swarm_factory, mavsdk_client) -> None:
    swarm = await swarm_factory(3)
    async with mavsdk_client(swarm.ports.api_port, 3) as systems:
        _, swarm_port = swarm.endpoints[0].local_address
        sniffer = mavlink.MAVLink(None, srcSystem=201, srcComponent=190)
        sniffer.robust_parsing = True
        loop = asyncio.get_running_loop()
        received: list[Any] = []

        class Peer(asyncio.DatagramProtocol):
            def datagram_received(self, data: bytes, addr: Any) -> None:
                received.extend(sniffer.parse_buffer(data) or [])

        transport, _ = await loop.create_datagram_endpoint(
            Peer, local_addr=("127.0.0.1", 0), remote_addr=("127.0.0.1", swarm_port))
        try:
            unroutable = swarm.endpoints[0].stats.unroutable
            for _ in range(3):  # ARM, TAKEOFF to system 42, which does not exist
                transport.sendto(mavlink.MAVLink_command_long_message(
                    42, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0).pack(sniffer))
                transport.sendto(mavlink.MAVLink_command_long_message(
                    42, 1, 22, 0, 0, 0, 0, 0, 0, 0, 0).pack(sniffer))
            await asyncio.sleep(1.2)
            assert received, "the swarm should stream to a peer that talked to it"
            assert swarm.endpoints[0].stats.unroutable >= unroutable + 6
            acks = [m for m in received if m.get_type() == "COMMAND_ACK"
                    and m.target_system == 201]
            assert acks == []
            assert 42 not in {m.get_srcSystem() for m in received}
            for k in range(1, 4):
                assert not swarm.fleet.autopilots[k - 1].armed
                assert "arm" not in kinds(swarm, k)

            # the others are undisturbed: still connected, still obey MAVSDK
            for system in systems:
                assert await system.is_connected()
            await ActionAsync(systems[1]).arm()
            assert swarm.fleet.autopilots[1].armed
            assert not swarm.fleet.autopilots[0].armed and not swarm.fleet.autopilots[2].armed
        finally:
            transport.close()
