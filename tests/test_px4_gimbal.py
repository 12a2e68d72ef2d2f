"""PX4 conformance in memory: a gimbal component (MAVLink gimbal protocol v2) on a vehicle
whose scenario asks for one: its manager announces it, DO_GIMBAL_MANAGER_PITCHYAW aims it
(the device's attitude follows), control is taken and respected; without one, gimbal
commands are unsupported."""

from __future__ import annotations

import dataclasses
import math

import pytest

from emulator.mavlink.gimbal import SLEW_RATE_DEG_S, _q_to_pitch_yaw_deg
from emulator.scenario import ScenarioError, default_scenario, scenario_from_dict
from emulator.scenario_export import scenario_to_dict
from mavlink_vocabulary import MavCmd, MavResult
from tests.memory_link import MemoryLink

NAN = math.nan


def _gimbal_link() -> MemoryLink:
    scenario = default_scenario(2)
    first = dataclasses.replace(scenario.vehicles[0], gimbal=True)
    return MemoryLink(2, scenario=dataclasses.replace(
        scenario, vehicles=(first, *scenario.vehicles[1:])), telemetry=False)


def _attitude(link: MemoryLink, since: int) -> tuple[float, float]:
    status = link.messages("GIMBAL_DEVICE_ATTITUDE_STATUS", system=1, since=since)[-1]
    assert status.get_srcComponent() == 154
    return _q_to_pitch_yaw_deg(status.q)


def test_the_gimbal_is_announced_and_aimed_by_pitchyaw() -> None:
    link = _gimbal_link()
    since = len(link.received)
    assert link.command_long(1, MavCmd.REQUEST_MESSAGE, 280).result == MavResult.ACCEPTED
    [info] = link.messages("GIMBAL_MANAGER_INFORMATION", since=since)
    assert info.gimbal_device_id == 154 and info.get_srcComponent() == 1
    assert math.degrees(info.pitch_min) == pytest.approx(-90.0)
    link.advance(1.1)  # the device's heartbeat, the manager's status, the attitude at 10 Hz
    beats = link.messages("HEARTBEAT", system=1, where=lambda m: m.get_srcComponent() == 154)
    assert beats and beats[0].type == 26
    assert len(link.messages("GIMBAL_DEVICE_ATTITUDE_STATUS", system=1)) >= 10
    assert link.messages("GIMBAL_MANAGER_STATUS", system=1)
    # pitch down 60, yaw right 30: it slews there at SLEW_RATE_DEG_S (simulated time)
    t0 = link.fleet.now_s
    ack = link.command_long(1, MavCmd.DO_GIMBAL_MANAGER_PITCHYAW, -60.0, 30.0, NAN, NAN, 0, 0,
                            154)
    assert ack.result == MavResult.ACCEPTED
    link.advance(0.3)
    status = link.messages("GIMBAL_DEVICE_ATTITUDE_STATUS", system=1)[-1]
    pitch, _ = _q_to_pitch_yaw_deg(status.q)
    assert pitch == pytest.approx(-SLEW_RATE_DEG_S * (status.time_boot_ms / 1e3 - t0), abs=0.5)
    since = len(link.received)
    link.advance(1.0)
    assert _attitude(link, since) == pytest.approx((-60.0, 30.0), abs=0.01)
    [event] = link.fleet.recorder.events("d1", kinds="gimbal")
    assert (event.data["pitch_deg"], event.data["yaw_deg"]) == (-60.0, 30.0)
    # the vehicle without a gimbal
    assert link.command_long(2, MavCmd.DO_GIMBAL_MANAGER_PITCHYAW, -10.0, 0.0).result == \
        MavResult.UNSUPPORTED
    assert link.command_long(2, MavCmd.REQUEST_MESSAGE, 280).result == MavResult.DENIED
    assert not link.messages("HEARTBEAT", system=2, where=lambda m: m.get_srcComponent() == 154)


def test_control_is_taken_and_bad_aims_change_nothing() -> None:
    link = _gimbal_link()
    gimbal = link.swarm.links[0].gimbal
    assert gimbal is not None
    since = len(link.received)
    ack = link.command_long(1, MavCmd.DO_GIMBAL_MANAGER_CONFIGURE, -2.0, -2.0)  # take control
    assert ack.result == MavResult.ACCEPTED
    [status] = link.messages("GIMBAL_MANAGER_STATUS", since=since)
    assert (status.primary_control_sysid, status.primary_control_compid) == (255, 190)
    for params in ((-120.0, 0.0), (0.0, 270.0), (math.inf, 0.0)):
        ack = link.command_long(1, MavCmd.DO_GIMBAL_MANAGER_PITCHYAW, *params)
        assert ack.result == MavResult.DENIED, params
    ack = link.command_long(1, MavCmd.DO_GIMBAL_MANAGER_PITCHYAW, -10.0, 0.0, NAN, NAN, 0, 0, 9)
    assert ack.result == MavResult.DENIED  # no gimbal device 9
    # another ground station is refused while this one is in control
    other = link.mav.srcSystem
    link.mav.srcSystem = 200
    try:
        ack = link.command_long(1, MavCmd.DO_GIMBAL_MANAGER_PITCHYAW, -45.0, 0.0)
        assert ack.result == MavResult.DENIED
        link.send(link.mav.gimbal_manager_set_pitchyaw_encode(1, 1, 0, 0, -0.5, 0.0, NAN, NAN))
    finally:
        link.mav.srcSystem = other
    link.advance(1.0)
    assert (gimbal.pitch_deg, gimbal.yaw_deg) == (0.0, 0.0)
    assert not link.fleet.recorder.events("d1", kinds="gimbal")
    # the controller streams GIMBAL_MANAGER_SET_PITCHYAW (radians); earth-frame yaw lock
    link.send(link.mav.gimbal_manager_set_pitchyaw_encode(1, 1, 16, 0, math.radians(-30.0),
                                                          math.radians(90.0), NAN, NAN))
    link.advance(2.0)
    heading = float(link.fleet.dyn.yaw_deg[0])
    assert gimbal.pitch_deg == pytest.approx(-30.0)
    assert (heading + gimbal.yaw_deg) % 360.0 == pytest.approx(90.0, abs=0.01)
    assert link.command_long(1, MavCmd.DO_GIMBAL_MANAGER_CONFIGURE, -3.0).result == \
        MavResult.ACCEPTED
    assert gimbal.primary == (0, 0)


ABSURD = (NAN, math.inf, -math.inf, 0.0, -0.0, 1e30, -1e30, 3.4e38, -91.0, 31.0, 181.0, -2.0,
          -3.0, 255.0, 256.0, 154.0)


def test_absurd_gimbal_input_leaves_it_within_its_limits_and_answering() -> None:
    link = _gimbal_link()
    gimbal = link.swarm.links[0].gimbal
    assert gimbal is not None
    for i, value in enumerate(ABSURD):
        for slot in range(7):
            params = [-20.0, 10.0, NAN, NAN, 0.0, 0.0, 0.0]
            params[slot] = value
            for command in (MavCmd.DO_GIMBAL_MANAGER_PITCHYAW, MavCmd.DO_GIMBAL_MANAGER_CONFIGURE):
                ack = link.command_long(1, command, *params)
                assert ack.result in (MavResult.ACCEPTED, MavResult.DENIED)
        f = ABSURD[(i + 3) % len(ABSURD)]
        link.send(link.mav.gimbal_manager_set_pitchyaw_encode(1, 1, i, 0, value, f, f, value))
        link.send(link.mav.gimbal_manager_set_attitude_encode(1, 1, i, 0, (value, f, 0, 1),
                                                              value, f, value))
        link.advance(0.2)
        assert -90.0 <= gimbal.pitch_deg <= 30.0 and -180.0 <= gimbal.yaw_deg <= 180.0
    link.command_long(1, MavCmd.DO_GIMBAL_MANAGER_CONFIGURE, -2.0, -2.0)
    assert link.command_long(1, MavCmd.DO_GIMBAL_MANAGER_PITCHYAW, -10.0, 5.0).result == \
        MavResult.ACCEPTED
    link.advance(3.0)  # from anywhere within the limits
    assert (gimbal.pitch_deg, gimbal.yaw_deg) == pytest.approx((-10.0, 5.0))
    assert link.network.stats.handler_errors == 0


def _session(**drone: object) -> dict:
    return {"name": "g", "targets": [], "obstacles": [],
            "drones": [{"id": "d1", "name": "D", "model": "M", "max_speed": 10,
                        "max_altitude": 100, "battery_capacity": 80,
                        "position": {"x": 0, "y": 0, "z": 0}, **drone}]}


def test_the_gimbal_is_an_optional_scenario_field_kept_by_the_export() -> None:
    assert not scenario_from_dict(_session(), source="g.json").vehicles[0].gimbal
    with_gimbal = scenario_from_dict(_session(gimbal=True), source="g.json")
    assert with_gimbal.vehicles[0].gimbal
    assert scenario_to_dict(with_gimbal)["drones"][0]["gimbal"] is True
    assert "gimbal" not in scenario_to_dict(default_scenario(1))["drones"][0]
    with pytest.raises(ScenarioError, match=r"gimbal.*true or false"):
        scenario_from_dict(_session(gimbal="yes"), source="g.json")


def test_mission_gimbal_and_video_items_are_acted_on() -> None:
    link = _gimbal_link()
    origin = link.fleet.world.origin
    lat, lon, _ = origin.to_geodetic(0.0, 30.0, 0.0)
    lat0, lon0, _ = origin.to_geodetic(0.0, 0.0, 0.0)
    items = [
        link.mission_item(1, 0, MavCmd.NAV_TAKEOFF, lat0, lon0, 10.0),
        link.mission_item(1, 1, MavCmd.SET_CAMERA_MODE, 0, 0, 0.0, params=(0.0, 1.0, NAN, NAN)),
        link.mission_item(1, 2, MavCmd.VIDEO_START_CAPTURE, 0, 0, 0.0,
                          params=(0.0, 0.0, NAN, NAN)),
        link.mission_item(1, 3, MavCmd.DO_GIMBAL_MANAGER_PITCHYAW, 0, 0, 0.0,
                          params=(-90.0, 0.0, NAN, NAN)),
        link.mission_item(1, 4, MavCmd.NAV_WAYPOINT, lat, lon, 10.0),
        link.mission_item(1, 5, MavCmd.VIDEO_STOP_CAPTURE, 0, 0, 0.0,
                          params=(0.0, NAN, NAN, NAN)),
    ]
    assert link.upload_mission(1, items).type == 0
    assert link.command_long(1, MavCmd.COMPONENT_ARM_DISARM, 1.0).result == MavResult.ACCEPTED
    assert link.command_long(1, MavCmd.DO_SET_MODE, 1, 4, 4).result == MavResult.ACCEPTED
    link.wait_for("MISSION_ITEM_REACHED", system=1, where=lambda m: m.seq == 4, within_s=60.0)
    link.advance(0.1)
    kinds = [e.kind for e in link.fleet.recorder.events(
        "d1", kinds=("video_start", "gimbal", "video_stop"))]
    assert kinds == ["video_start", "gimbal", "video_stop"]
    [stop] = link.fleet.recorder.events("d1", kinds="video_stop")
    assert stop.data["position_m"][1] == pytest.approx(30.0, abs=2.5)  # at the waypoint
    link.advance(2.0)
    gimbal = link.swarm.links[0].gimbal
    assert gimbal is not None and gimbal.pitch_deg == -90.0
