"""The swarm's MAVLink network in memory (tests/memory_link.py): a pymavlink client and the
sans-I/O protocol object, paired without sockets, time advanced by the test. The same
behaviours as the UDP tests, deterministic and fast; the MAVSDK-over-UDP tests stay the
integration tier."""

from __future__ import annotations

import math

import pytest

from emulator.clock import ClockConfig
from emulator.flight.modes import FlightMode
from emulator.link_faults import LinkFaults, LinkProfile
from emulator.scenario import default_scenario
from emulator.swarm import PortPlan, Swarm
from mavlink_vocabulary import (
    MavCmd,
    MavComponent,
    MavFrame,
    MavLandedState,
    MavMissionResult,
    MavParamType,
    MavResult,
    MessageId,
)
from tests.frame_fuzz import FrameFuzzer
from tests.memory_fuzz import recover_and_fly, storm
from tests.memory_link import CLIENT, MemoryLink, mavlink

FUZZ_SEED = 20261125
FUZZ_FRAMES = 20_000


def test_a_command_is_acknowledged_at_once_and_the_vehicle_takes_off() -> None:
    link = MemoryLink(2)
    ack = link.command_long(1, MavCmd.COMPONENT_ARM_DISARM, 1.0)
    assert (ack.result, ack.target_system, ack.target_component) == (MavResult.ACCEPTED, 255, 190)
    assert link.fleet.autopilots[0].armed and not link.fleet.autopilots[1].armed
    link.arm_and_take_off(1)
    ap = link.fleet.autopilots[0]
    assert ap.in_air and ap.position_m[2] > 1.0
    assert [e.kind for e in link.swarm.recorder.events("d1", kinds=("arm", "takeoff"))] == [
        "arm", "takeoff"]
    # telemetry reached the client on the way: heartbeats of both vehicles, at their rate
    beats = link.messages("HEARTBEAT", system=2)
    assert len(beats) >= 2 and all(m.get_srcComponent() in (1, 100) for m in beats)


def test_a_refusal_comes_with_its_reason_after_the_ack() -> None:
    link = MemoryLink(1)
    since = link.send(link.mav.command_long_encode(1, 1, MavCmd.COMPONENT_ARM_DISARM, 0,
                                                   7.0, 0, 0, 0, 0, 0, 0))
    kinds = [m.get_type() for m in link.messages(("COMMAND_ACK", "STATUSTEXT"), since=since)]
    assert kinds == ["COMMAND_ACK", "STATUSTEXT"]
    ack, text = link.messages(("COMMAND_ACK", "STATUSTEXT"), since=since)
    assert ack.result == MavResult.DENIED and "param1 must be 0 or 1" in text.text
    assert link.command_long(1, 31999).result == MavResult.UNSUPPORTED


def test_follow_up_messages_come_after_the_ack() -> None:
    link = MemoryLink(1)
    since = link.send(link.mav.command_long_encode(
        1, 1, MavCmd.REQUEST_MESSAGE, 0, MessageId.AUTOPILOT_VERSION, 0, 0, 0, 0, 0, 0))
    kinds = [m.get_type() for m in link.messages(since=since)]
    assert kinds[:2] == ["COMMAND_ACK", "AUTOPILOT_VERSION"], kinds
    version = link.messages("AUTOPILOT_VERSION", since=since)[0]
    assert version.capabilities & 8192  # MAVLINK2
    # a refused request sends nothing after its ACK
    since = link.send(link.mav.command_long_encode(1, 1, MavCmd.REQUEST_MESSAGE, 0, 99999,
                                                   0, 0, 0, 0, 0, 0))
    assert [m.get_type() for m in link.messages(since=since)] == ["COMMAND_ACK"]


def test_a_photo_is_reported_after_its_ack_and_once_per_capture_sequence() -> None:
    link = MemoryLink(1)
    link.arm_and_take_off(1)

    def capture(sequence: float) -> list[str]:
        since = link.send(link.mav.command_long_encode(
            1, MavComponent.CAMERA, MavCmd.IMAGE_START_CAPTURE, 0, 0, 0, 1, sequence, 0, 0, 0))
        return [m.get_type() for m in link.messages(("COMMAND_ACK", "CAMERA_IMAGE_CAPTURED"),
                                                    since=since)]

    assert capture(1.0) == ["COMMAND_ACK", "CAMERA_IMAGE_CAPTURED"]
    assert capture(1.0) == ["COMMAND_ACK", "CAMERA_IMAGE_CAPTURED"]  # the report again
    assert link.fleet.autopilots[0].photo_count == 1
    assert capture(2.0) == ["COMMAND_ACK", "CAMERA_IMAGE_CAPTURED"]
    assert link.fleet.autopilots[0].photo_count == 2
    acks = link.messages("COMMAND_ACK", where=lambda m: m.command == MavCmd.IMAGE_START_CAPTURE)
    assert {m.get_srcComponent() for m in acks} == {MavComponent.CAMERA}


def test_a_retransmitted_command_is_answered_again_not_executed_again() -> None:
    link = MemoryLink(1)
    frame = link.pack(link.mav.command_long_encode(1, 1, MavCmd.COMPONENT_ARM_DISARM, 0,
                                                   1.0, 0, 0, 0, 0, 0, 0))
    first = link.send_raw(frame)
    second = link.send_raw(frame)
    acks = link.messages("COMMAND_ACK", since=first)
    assert [m.result for m in acks] == [MavResult.ACCEPTED, MavResult.ACCEPTED]
    assert second > first and link.swarm.links[0].dedup.duplicates == 1
    assert len(link.swarm.recorder.events("d1", kinds=("arm",))) == 1


def test_mission_upload_download_and_flight() -> None:
    link = MemoryLink(1)
    origin = link.fleet.world.origin
    points = [(0.0, 0.0), (0.0, 20.0), (15.0, 20.0)]
    items = []
    for seq, (x, y) in enumerate(points):
        lat, lon, _ = origin.to_geodetic(x, y, 0.0)
        items.append(link.mission_item(1, seq, MavCmd.NAV_WAYPOINT, lat, lon, 10.0))
    assert link.upload_mission(1, items).type == MavMissionResult.ACCEPTED
    got = link.download_mission(1)
    assert [(m.seq, m.command, m.x, m.y) for m in got] == [
        (m.seq, m.command, m.x, m.y) for m in items]
    assert link.command_long(1, MavCmd.COMPONENT_ARM_DISARM, 1.0).result == 0
    since = len(link.received)
    assert link.command_long(1, MavCmd.MISSION_START, 0, 0).result == 0
    link.wait_for("MISSION_ITEM_REACHED", system=1, since=since, within_s=120.0,
                  where=lambda m: m.seq == len(items) - 1)
    reached = [m.seq for m in link.messages("MISSION_ITEM_REACHED", since=since)]
    assert reached == list(range(len(items)))
    x, y, _ = link.fleet.autopilots[0].position_m
    assert (x, y) == pytest.approx(points[-1], abs=1.5)


def test_a_mission_item_out_of_range_is_refused_with_the_dialects_code() -> None:
    link = MemoryLink(1)
    origin = link.fleet.world.origin
    lat, lon, _ = origin.to_geodetic(10.0, 0.0, 0.0)
    items = [link.mission_item(1, 0, MavCmd.NAV_WAYPOINT, lat, lon, 10.0),
             link.mission_item(1, 1, MavCmd.NAV_WAYPOINT, 91.0, lon, 10.0)]
    ack = link.upload_mission(1, items)
    assert ack.type == MavMissionResult.INVALID_PARAM5_X
    assert link.fleet.autopilots[0].mission.total == 0


def test_a_lost_mission_item_is_requested_again_on_the_links_timer() -> None:
    link = MemoryLink(1)
    since = link.send(link.mav.mission_count_encode(1, 1, 2, 0))
    first = link.wait_for("MISSION_REQUEST_INT", since=since, within_s=0.0)
    assert first.seq == 0
    link.advance(0.3)  # the client "lost" the request: the vehicle asks again
    again = link.messages("MISSION_REQUEST_INT", since=since)
    assert [m.seq for m in again] == [0, 0]


def test_link_faults_in_memory_drop_and_delay_on_the_protocols_timer() -> None:
    faults = LinkFaults(seed=3, uplink=LinkProfile(latency_ms=200.0))
    link = MemoryLink(1, link_faults=faults, telemetry=False)
    network = link.network
    since = link.send(link.mav.command_long_encode(1, 1, MavCmd.COMPONENT_ARM_DISARM, 0,
                                                   1.0, 0, 0, 0, 0, 0, 0))
    assert not link.messages("COMMAND_ACK", since=since)  # the command is still on its way
    due = network.next_timer()
    assert due is not None and due == pytest.approx(link.now + 0.2)
    link.now = due - 0.01
    assert not network.handle_timer(link.now)
    link.now = due
    link.collect()
    assert link.messages("COMMAND_ACK", since=since)[0].result == MavResult.ACCEPTED
    assert network.next_timer() is None

    lossy = MemoryLink(1, link_faults=LinkFaults(downlink=LinkProfile(loss=1.0)),
                       telemetry=False)
    since = lossy.send(lossy.mav.command_long_encode(1, 1, MavCmd.COMPONENT_ARM_DISARM, 0,
                                                     1.0, 0, 0, 0, 0, 0, 0))
    assert lossy.fleet.autopilots[0].armed  # executed, but its ACK was lost
    assert not lossy.messages(since=since)


def test_frames_for_unknown_systems_and_broadcast_pings_are_not_answered() -> None:
    link = MemoryLink(2, telemetry=False)
    since = link.send(link.mav.command_long_encode(9, 1, MavCmd.COMPONENT_ARM_DISARM, 0,
                                                   1.0, 0, 0, 0, 0, 0, 0))
    since = link.send(link.mav.ping_encode(1, 2, 0, 0))
    assert not link.messages(since=since)
    assert link.network.stats.unroutable == 1
    assert link.network.stats.peers == {CLIENT}


@pytest.mark.slow
def test_a_seeded_fuzz_storm_leaves_every_vehicle_answering_and_flying() -> None:
    n = 3
    link = MemoryLink(scenario=default_scenario(n))
    params = [dict(ap.params) for ap in link.fleet.autopilots]
    fuzzer = FrameFuzzer(FUZZ_SEED, systems=tuple(range(1, n + 1)))
    result = storm(link, fuzzer, FUZZ_FRAMES)
    print("memory fuzz:", result.line())
    assert result.frames == FUZZ_FRAMES
    assert result.frames_ok > FUZZ_FRAMES // 4 and result.frames_bad > FUZZ_FRAMES // 10
    assert link.network.stats.handler_errors == 0
    assert link.swarm.stats().internal_errors == 0
    kinds = {e.kind for k in range(n) for e in link.swarm.recorder.events(f"d{k + 1}")}
    assert {"arm", "takeoff", "mode"} <= kinds, kinds  # the storm really drove them
    for system in range(1, n + 1):
        recover_and_fly(link, system, params[system - 1])
    assert all(ap.in_air for ap in link.fleet.autopilots)
    assert all(math.isfinite(v) for v in link.fleet.dyn.position_m.ravel())
    # and the client sees it: every vehicle reports itself in the air
    since = len(link.received)
    for system in range(1, n + 1):
        state = link.wait_for("EXTENDED_SYS_STATE", system=system, since=since, within_s=2.0)
        assert state.landed_state == MavLandedState.IN_AIR


def test_a_float_mission_item_beyond_int32_degrees_still_downloads() -> None:
    link = MemoryLink(1, telemetry=False)
    lat, lon, _ = link.fleet.world.origin.to_geodetic(10.0, 0.0, 0.0)
    good = link.mission_item(1, 0, MavCmd.NAV_WAYPOINT, lat, lon, 10.0)
    # a DO command carries no position: its absurd x is kept, clamped to MISSION_ITEM_INT's
    # int32, so that the mission can still be downloaded
    huge = link.mav.mission_item_encode(1, 1, 1, 3, MavCmd.DO_CHANGE_SPEED, 0, 1, 1.0, 5.0,
                                        -1.0, 0.0, 1e30, -1e30, 0.0, 0)
    assert link.upload_mission(1, [good, huge]).type == MavMissionResult.ACCEPTED
    got = link.download_mission(1)
    assert [(m.seq, m.command) for m in got] == [(0, MavCmd.NAV_WAYPOINT),
                                                 (1, MavCmd.DO_CHANGE_SPEED)]
    assert (got[1].x, got[1].y) == (2**31 - 1, -(2**31))


def test_offboard_set_points_fly_and_their_loss_holds_on_the_links_timer() -> None:
    link = MemoryLink(1, telemetry=False)
    link.arm_and_take_off(1)
    ap = link.fleet.autopilots[0]
    x0, y0, z0 = ap.position_m

    def setpoint(north: float, east: float, down: float, frame: int = MavFrame.LOCAL_NED,
                 mask: int = 0xDF8) -> int:  # position only
        return link.send(link.mav.set_position_target_local_ned_encode(
            0, 1, 1, frame, mask, north, east, down, 0, 0, 0, 0, 0, 0, 0, 0))

    setpoint(y0 + 10.0, x0, -z0)
    assert link.command_long(1, MavCmd.DO_SET_MODE, 1, 6, 0).result == MavResult.ACCEPTED
    assert ap.mode is FlightMode.OFFBOARD
    for _ in range(40):  # 4 s of set-points at 10 Hz
        setpoint(y0 + 10.0, x0, -z0)
        link.advance(0.1)
    assert ap.position_m[1] == pytest.approx(y0 + 10.0, abs=1.0)
    # malformed set-points are ignored, each kind reported once
    since = setpoint(math.nan, 0.0, 0.0)
    setpoint(math.nan, 0.0, 0.0)
    setpoint(0.0, 0.0, 0.0, frame=MavFrame.MISSION)
    texts = [m.text for m in link.messages("STATUSTEXT", since=since)]
    assert texts == ["Offboard: set-point with NaN ignored", "Offboard: frame 2 unsupported"]
    # set-points stop: after COM_OF_LOSS_T of wall time the vehicle holds
    since = len(link.received)
    link.advance(ap.params["COM_OF_LOSS_T"] + 0.2)
    assert ap.mode is FlightMode.HOLD
    assert any(m.text.startswith("Offboard setpoints lost")
               for m in link.messages("STATUSTEXT", since=since))


def test_parameters_are_read_and_set_bytewise() -> None:
    link = MemoryLink(1, telemetry=False)
    since = link.send(link.mav.param_request_list_encode(1, 1))
    values = link.messages("PARAM_VALUE", since=since)
    assert len(values) == values[0].param_count == len(link.fleet.autopilots[0].params)
    since = link.send(link.mav.param_set_encode(1, 1, b"MPC_XY_CRUISE", 7.5,
                                                MavParamType.REAL32))
    echo = link.wait_for("PARAM_VALUE", since=since, within_s=0.0)
    assert (echo.param_id, echo.param_value) == ("MPC_XY_CRUISE", 7.5)
    assert link.fleet.autopilots[0].params["MPC_XY_CRUISE"] == 7.5
    since = link.send(link.mav.param_set_encode(1, 1, b"NO_SUCH_PARAM", 1.0,
                                                MavParamType.REAL32))
    assert [m.get_type() for m in link.messages(since=since)] == ["STATUSTEXT"]


def test_per_vehicle_networks_each_serve_their_own_vehicle() -> None:
    swarm = Swarm(default_scenario(3), clock=ClockConfig(stepped=True),
                  ports=PortPlan(bind_port=24600, api_port=24700, gcs_port=0, per_vehicle=True))
    assert len(swarm.networks) == 3
    mav = mavlink.MAVLink(None, srcSystem=255, srcComponent=190)
    for network in swarm.networks:
        network.open()
    arm_2 = mav.command_long_encode(2, 1, MavCmd.COMPONENT_ARM_DISARM, 0, 1, 0, 0, 0, 0, 0, 0)
    swarm.networks[0].receive_datagram(arm_2.pack(mav), CLIENT, 0.0)
    assert swarm.networks[0].stats.unroutable == 1 and not swarm.fleet.autopilots[1].armed
    swarm.networks[1].receive_datagram(arm_2.pack(mav), CLIENT, 0.0)
    assert swarm.fleet.autopilots[1].armed
    sent = swarm.networks[1].datagrams_to_send(0.0)
    # to the vehicle's own API port and to the client that spoke to it
    assert {addr for _, addr in sent} == {("127.0.0.1", 24701), CLIENT}
    assert not swarm.networks[0].datagrams_to_send(0.0)
