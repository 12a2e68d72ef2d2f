"""PX4 conformance in memory: fence plans (polygons and circles, inclusion and exclusion) and
rally points uploaded with the mission protocol, downloaded back, and acted on: a breach
triggers GF_ACTION, a destination outside the fence is refused, RTL goes to the closest rally
point; all checked against the ground truth."""

from __future__ import annotations

import math

import pytest

from emulator.flight.modes import FlightMode
from mavlink_vocabulary import MavCmd, MavComponent, MavFrame, MavMissionResult, MavMissionType
from mavlink_vocabulary import PositionTargetTypemask as Mask
from tests.memory_link import MemoryLink, mavlink

VELOCITY_ONLY = int(Mask.X_IGNORE | Mask.Y_IGNORE | Mask.Z_IGNORE | Mask.AX_IGNORE
                    | Mask.AY_IGNORE | Mask.AZ_IGNORE | Mask.YAW_IGNORE | Mask.YAW_RATE_IGNORE)


def _item(link: MemoryLink, seq: int, command: int, x_m: float, y_m: float, *,
          mission_type: int, param1: float = 0.0, alt_m: float = 0.0
          ) -> mavlink.MAVLink_mission_item_int_message:
    lat, lon, _ = link.fleet.world.origin.to_geodetic(x_m, y_m, 0.0)
    return link.mav.mission_item_int_encode(
        1, MavComponent.AUTOPILOT1, seq, MavFrame.GLOBAL_RELATIVE_ALT_INT, command, 0, 1,
        param1, 0.0, 0.0, 0.0, round(lat * 1e7), round(lon * 1e7), alt_m, mission_type)


def _upload(link: MemoryLink, items: list, mission_type: int) -> mavlink.MAVLink_message:
    since = link.send(link.mav.mission_count_encode(1, MavComponent.AUTOPILOT1, len(items),
                                                    mission_type))
    while True:
        m = link.wait_for(("MISSION_REQUEST_INT", "MISSION_ACK"), system=1, since=since,
                          within_s=1.0)
        if m.get_type() == "MISSION_ACK":
            assert m.mission_type == mission_type
            return m
        assert m.mission_type == mission_type
        since = link.send(items[m.seq])


def _download(link: MemoryLink, mission_type: int) -> list:
    since = link.send(link.mav.mission_request_list_encode(1, MavComponent.AUTOPILOT1,
                                                           mission_type))
    count = link.wait_for("MISSION_COUNT", system=1, since=since, within_s=0.0)
    assert count.mission_type == mission_type
    out = []
    for seq in range(count.count):
        since = link.send(link.mav.mission_request_int_encode(1, MavComponent.AUTOPILOT1, seq,
                                                              mission_type))
        out.append(link.wait_for("MISSION_ITEM_INT", system=1, since=since, within_s=0.0))
    return out


def _fence(link: MemoryLink) -> list:
    """An inclusion square of 100 m around the start, an exclusion circle of 10 m at (0, 30)."""
    inc = MavCmd.NAV_FENCE_POLYGON_VERTEX_INCLUSION
    square = [(-50.0, -50.0), (50.0, -50.0), (50.0, 50.0), (-50.0, 50.0)]
    items = [_item(link, i, inc, x, y, mission_type=MavMissionType.FENCE, param1=4.0)
             for i, (x, y) in enumerate(square)]
    items.append(_item(link, 4, MavCmd.NAV_FENCE_CIRCLE_EXCLUSION, 0.0, 30.0,
                       mission_type=MavMissionType.FENCE, param1=10.0))
    return items


def _summary(items: list) -> list[tuple]:
    return [(m.seq, m.command, m.x, m.y, m.param1, m.mission_type) for m in items]


def _reposition(link: MemoryLink, x_m: float, y_m: float, z_m: float) -> mavlink.MAVLink_message:
    lat, lon, alt = link.fleet.world.origin.to_geodetic(x_m, y_m, z_m)
    since = link.send(link.mav.command_int_encode(
        1, MavComponent.AUTOPILOT1, MavFrame.GLOBAL, MavCmd.DO_REPOSITION, 0, 0, math.nan, 1.0,
        0.0, math.nan, round(lat * 1e7), round(lon * 1e7), alt))
    return link.wait_for("COMMAND_ACK", system=1, since=since, within_s=0.0)


def test_fence_plan_is_stored_downloadable_and_enforced_with_gf_action() -> None:
    link = MemoryLink(1, telemetry=False)
    ap = link.fleet.autopilots[0]
    items = _fence(link)
    assert _upload(link, items, MavMissionType.FENCE).type == MavMissionResult.ACCEPTED
    assert _summary(_download(link, MavMissionType.FENCE)) == _summary(items)
    assert ap.mission.total == 0  # the mission is apart
    link.arm_and_take_off(1, 10.0)
    # a destination outside the fence or inside the exclusion zone is refused
    for x, y in [(80.0, 0.0), (0.0, 30.0)]:
        since = len(link.received)
        assert _reposition(link, x, y, 10.0).result == 2
        assert any("outside the geofence" in m.text
                   for m in link.messages("STATUSTEXT", since=since))
    # flown out by velocity set-points: GF_ACTION 2 (the default) holds
    link.send(link.mav.set_position_target_local_ned_encode(
        0, 1, 1, MavFrame.LOCAL_NED, VELOCITY_ONLY, 0, 0, 0, 0.0, 5.0, 0.0, 0, 0, 0, 0, 0))
    assert link.command_long(1, MavCmd.DO_SET_MODE, 1, 6, 0).result == 0
    for _ in range(200):
        if ap.mode is not FlightMode.OFFBOARD:
            break
        link.send(link.mav.set_position_target_local_ned_encode(
            0, 1, 1, MavFrame.LOCAL_NED, VELOCITY_ONLY, 0, 0, 0, 0.0, 5.0, 0.0, 0, 0, 0, 0, 0))
        link.advance(0.1)
    assert ap.mode is FlightMode.HOLD
    breach = link.fleet.recorder.events("d1", kinds="failsafe")
    assert [e.data["reason"] for e in breach] == ["geofence"]
    assert breach[0].data["position_m"][0] == pytest.approx(50.0, abs=0.2)  # the fence's edge
    link.advance(5.0)  # it brakes (5 m/s at MPC_ACC_HOR) and holds
    assert ap.position_m[0] < 55.0 and link.fleet.dyn.speed_m_s(0) < 0.05


def test_fence_breach_with_gf_action_return_flies_home() -> None:
    link = MemoryLink(1, telemetry=False)
    ap = link.fleet.autopilots[0]
    ap.set_param("GF_ACTION", 3)
    assert _upload(link, _fence(link), MavMissionType.FENCE).type == MavMissionResult.ACCEPTED
    link.arm_and_take_off(1, 10.0)
    link.send(link.mav.set_position_target_local_ned_encode(
        0, 1, 1, MavFrame.LOCAL_NED, VELOCITY_ONLY, 0, 0, 0, -6.0, 0.0, 0.0, 0, 0, 0, 0, 0))
    assert link.command_long(1, MavCmd.DO_SET_MODE, 1, 6, 0).result == 0
    for _ in range(200):
        if ap.mode is not FlightMode.OFFBOARD:
            break
        link.send(link.mav.set_position_target_local_ned_encode(
            0, 1, 1, MavFrame.LOCAL_NED, VELOCITY_ONLY, 0, 0, 0, -6.0, 0.0, 0.0, 0, 0, 0, 0, 0))
        link.advance(0.1)
    assert ap.mode is FlightMode.RTL
    link.advance(90.0)
    assert not ap.in_air and math.hypot(*ap.position_m[:2]) < 0.5


def test_arming_outside_an_inclusion_fence_is_refused() -> None:
    link = MemoryLink(1, telemetry=False)
    inc = MavCmd.NAV_FENCE_CIRCLE_INCLUSION
    far = [_item(link, 0, inc, 200.0, 0.0, mission_type=MavMissionType.FENCE, param1=20.0)]
    assert _upload(link, far, MavMissionType.FENCE).type == MavMissionResult.ACCEPTED
    assert link.command_long(1, MavCmd.COMPONENT_ARM_DISARM, 1.0).result == 2
    assert not link.fleet.autopilots[0].armed
    # cleared (type ALL clears every plan), the vehicle arms
    since = link.send(link.mav.mission_clear_all_encode(1, 1, MavMissionType.ALL))
    assert link.wait_for("MISSION_ACK", system=1, since=since, within_s=0.0).type == 0
    assert _download(link, MavMissionType.FENCE) == []
    assert link.command_long(1, MavCmd.COMPONENT_ARM_DISARM, 1.0).result == 0


@pytest.mark.parametrize("vertices", [2, 5])
def test_malformed_fence_plan_is_refused_and_keeps_the_old_one(vertices: int) -> None:
    link = MemoryLink(1, telemetry=False)
    items = _fence(link)
    assert _upload(link, items, MavMissionType.FENCE).type == MavMissionResult.ACCEPTED
    inc = MavCmd.NAV_FENCE_POLYGON_VERTEX_INCLUSION
    bad = [_item(link, i, inc, 10.0 * i, 10.0 * (i % 2), mission_type=MavMissionType.FENCE,
                 param1=float(vertices)) for i in range(3)]
    since = len(link.received)
    assert _upload(link, bad, MavMissionType.FENCE).type == MavMissionResult.INVALID
    assert any("polygon" in m.text for m in link.messages("STATUSTEXT", since=since))
    assert _summary(_download(link, MavMissionType.FENCE)) == _summary(items)


def test_rtl_goes_to_the_closest_rally_point() -> None:
    link = MemoryLink(1, telemetry=False)
    ap = link.fleet.autopilots[0]
    rally = [_item(link, 0, MavCmd.NAV_RALLY_POINT, 100.0, 100.0,
                   mission_type=MavMissionType.RALLY, alt_m=20.0),
             _item(link, 1, MavCmd.NAV_RALLY_POINT, -150.0, 0.0,
                   mission_type=MavMissionType.RALLY, alt_m=20.0)]
    assert _upload(link, rally, MavMissionType.RALLY).type == MavMissionResult.ACCEPTED
    assert _summary(_download(link, MavMissionType.RALLY)) == _summary(rally)
    link.arm_and_take_off(1, 10.0)
    assert _reposition(link, 80.0, 60.0, 15.0).result == 0
    link.advance(30.0)
    assert link.command_long(1, MavCmd.DO_SET_MODE, 1, 4, 5).result == 0  # RTL
    assert ap.mode is FlightMode.RTL
    link.advance(120.0)
    assert not ap.in_air
    assert ap.position_m[:2] == pytest.approx((100.0, 100.0), abs=0.5)
    landed = link.fleet.recorder.events("d1", kinds="landed")[-1]
    assert landed.data["position_m"][:2] == pytest.approx([100.0, 100.0], abs=0.5)


def test_a_mission_crossing_the_fence_is_refused_at_upload() -> None:
    link = MemoryLink(1, telemetry=False)
    assert _upload(link, _fence(link), MavMissionType.FENCE).type == MavMissionResult.ACCEPTED
    origin = link.fleet.world.origin
    inside = [link.mission_item(1, 0, MavCmd.NAV_WAYPOINT,
                                *origin.to_geodetic(0.0, -30.0, 0.0)[:2], 10.0)]
    assert link.upload_mission(1, inside).type == MavMissionResult.ACCEPTED
    outside = [link.mission_item(1, 0, MavCmd.NAV_WAYPOINT,
                                 *origin.to_geodetic(0.0, -30.0, 0.0)[:2], 10.0),
               link.mission_item(1, 1, MavCmd.NAV_WAYPOINT,
                                 *origin.to_geodetic(0.0, 30.0, 0.0)[:2], 10.0)]  # excluded
    since = len(link.received)
    assert link.upload_mission(1, outside).type == MavMissionResult.INVALID
    assert any("Mission item 1 outside the geofence" in m.text
               for m in link.messages("STATUSTEXT", since=since))
    assert link.fleet.autopilots[0].mission.total == 1  # the old mission kept
