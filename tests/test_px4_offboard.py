"""PX4 conformance in memory: offboard yaw rates (LOCAL_NED and BODY_NED), per-vehicle local
origins and an offboard set-point on the ground, each checked against the ground truth
(`fleet.dyn`, the recorder's trajectory)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emulator.flight.modes import FlightMode
from mavlink_vocabulary import MavCmd, MavFrame, MavResult
from mavlink_vocabulary import PositionTargetTypemask as Mask
from tests.memory_link import MemoryLink

# velocity and yaw rate only (MAVSDK's set_velocity_body / set_velocity_ned with yawspeed)
VELOCITY_YAW_RATE = int(Mask.X_IGNORE | Mask.Y_IGNORE | Mask.Z_IGNORE | Mask.AX_IGNORE
                        | Mask.AY_IGNORE | Mask.AZ_IGNORE | Mask.YAW_IGNORE)
POSITION_ONLY = 0xDF8


def _velocity(link: MemoryLink, system: int, frame: int, vx: float, vy: float, vz: float,
              yaw_rate_deg_s: float) -> None:
    link.send(link.mav.set_position_target_local_ned_encode(
        0, system, 1, frame, VELOCITY_YAW_RATE, 0, 0, 0, vx, vy, vz, 0, 0, 0, 0,
        math.radians(yaw_rate_deg_s)))


def _fly_setpoints(link: MemoryLink, seconds: float, send) -> None:
    for _ in range(round(seconds / 0.1)):  # set-points at 10 Hz
        send()
        link.advance(0.1)


def _offboard(link: MemoryLink, system: int) -> None:
    assert link.command_long(system, MavCmd.DO_SET_MODE, 1, 6, 0).result == MavResult.ACCEPTED


def _heading_turned_deg(yaw_deg: np.ndarray) -> float:
    """Total signed heading change along a series of headings (unwrapped)."""
    return float(np.sum((np.diff(yaw_deg) + 180.0) % 360.0 - 180.0))


@pytest.mark.parametrize("frame", [MavFrame.LOCAL_NED, MavFrame.BODY_NED])
def test_offboard_yaw_rate_turns_the_heading_at_the_asked_rate(frame: int) -> None:
    link = MemoryLink(1, telemetry=False)
    link.arm_and_take_off(1)
    ap = link.fleet.autopilots[0]
    _velocity(link, 1, frame, 0.0, 0.0, 0.0, 30.0)
    _offboard(link, 1)
    _fly_setpoints(link, 1.0, lambda: _velocity(link, 1, frame, 0.0, 0.0, 0.0, 30.0))
    t0 = link.fleet.now_s
    _fly_setpoints(link, 6.0, lambda: _velocity(link, 1, frame, 0.0, 0.0, 0.0, 30.0))
    rows = link.fleet.recorder.trajectory("d1")
    window = rows[rows[:, 0] >= t0]
    turned = _heading_turned_deg(window[:, 4])
    assert turned / (window[-1, 0] - window[0, 0]) == pytest.approx(30.0, rel=0.03)
    # a negative rate turns the other way
    _fly_setpoints(link, 2.0, lambda: _velocity(link, 1, frame, 0.0, 0.0, 0.0, -20.0))
    t1 = link.fleet.now_s
    _fly_setpoints(link, 3.0, lambda: _velocity(link, 1, frame, 0.0, 0.0, 0.0, -20.0))
    rows = link.fleet.recorder.trajectory("d1")
    window = rows[rows[:, 0] >= t1]
    assert _heading_turned_deg(window[:, 4]) / (window[-1, 0] - window[0, 0]) == pytest.approx(
        -20.0, rel=0.03)
    assert ap.mode is FlightMode.OFFBOARD


def test_body_velocity_with_yaw_rate_flies_a_circle() -> None:
    link = MemoryLink(1, telemetry=False)
    link.arm_and_take_off(1)
    speed_m_s, rate_deg_s = 3.0, 30.0
    radius_m = speed_m_s / math.radians(rate_deg_s)  # 5.73 m

    def send() -> None:
        _velocity(link, 1, MavFrame.BODY_NED, speed_m_s, 0.0, 0.0, rate_deg_s)

    send()
    _offboard(link, 1)
    _fly_setpoints(link, 4.0, send)  # settle onto the circle
    t0 = link.fleet.now_s
    _fly_setpoints(link, 12.0, send)  # one full turn at 30 deg/s
    rows = link.fleet.recorder.trajectory("d1")
    xy = rows[rows[:, 0] >= t0][:, 1:3]
    center = xy.mean(axis=0)
    r = np.hypot(*(xy - center).T)
    assert r.mean() == pytest.approx(radius_m, rel=0.05)
    assert r.max() - r.min() < 0.3  # a circle, not a straight line
    # the same set-point in LOCAL_NED without a yaw rate flies a straight line
    assert np.ptp(xy[:, 0]) < 2.5 * radius_m and np.ptp(xy[:, 1]) < 2.5 * radius_m


def test_local_position_ned_is_about_each_vehicles_own_origin() -> None:
    link = MemoryLink(3)
    link.advance(1.0)
    for system in (1, 2, 3):
        m = link.messages("LOCAL_POSITION_NED", system=system)[-1]
        assert (m.x, m.y, m.z) == pytest.approx((0.0, 0.0, 0.0), abs=1e-6)
    # the same local set-point sends each vehicle to its own spot (5 m apart east)
    for system in (2, 3):
        link.arm_and_take_off(system)
    for system in (2, 3):
        link.send(link.mav.set_position_target_local_ned_encode(
            0, system, 1, MavFrame.LOCAL_NED, POSITION_ONLY, 10.0, 0.0, -8.0,
            0, 0, 0, 0, 0, 0, 0, 0))
        _offboard(link, system)
    _fly_setpoints(link, 8.0, lambda: [link.send(link.mav.set_position_target_local_ned_encode(
        0, s, 1, MavFrame.LOCAL_NED, POSITION_ONLY, 10.0, 0.0, -8.0, 0, 0, 0, 0, 0, 0, 0, 0))
        for s in (2, 3)])
    aps = link.fleet.autopilots
    assert aps[1].position_m == pytest.approx((5.0, 10.0, 8.0), abs=0.3)
    assert aps[2].position_m == pytest.approx((10.0, 10.0, 8.0), abs=0.3)


def test_shared_local_origin_is_an_option() -> None:
    link = MemoryLink(2)
    link.fleet.share_local_origin()
    link.advance(1.0)
    m = link.messages("LOCAL_POSITION_NED", system=2)[-1]
    assert (m.x, m.y) == pytest.approx((0.0, 5.0), abs=1e-6)  # 5 m east of the session origin


def test_offboard_setpoint_on_the_ground_lands_and_disarms() -> None:
    link = MemoryLink(1, telemetry=False)
    link.arm_and_take_off(1, 6.0)
    ap = link.fleet.autopilots[0]

    def send() -> None:
        link.send(link.mav.set_position_target_local_ned_encode(
            0, 1, 1, MavFrame.LOCAL_NED, POSITION_ONLY, 3.0, 0.0, 0.0, 0, 0, 0, 0, 0, 0, 0, 0))

    send()
    _offboard(link, 1)
    _fly_setpoints(link, 15.0, send)
    kinds = [e.kind for e in link.fleet.recorder.events("d1")]
    assert "landed" in kinds and kinds[-1] == "disarm"
    assert not ap.armed and not ap.in_air
    assert ap.position_m == pytest.approx((0.0, 3.0, 0.0), abs=0.3)


def test_offboard_on_the_ground_without_a_climb_disarms_after_the_preflight_delay() -> None:
    link = MemoryLink(1, telemetry=False)
    ap = link.fleet.autopilots[0]
    ap.set_param("COM_DISARM_PRFLT", 5.0)

    def send() -> None:
        link.send(link.mav.set_position_target_local_ned_encode(
            0, 1, 1, MavFrame.LOCAL_NED, POSITION_ONLY, 3.0, 0.0, 0.0, 0, 0, 0, 0, 0, 0, 0, 0))

    assert link.command_long(1, MavCmd.COMPONENT_ARM_DISARM, 1.0).result == 0
    send()
    _offboard(link, 1)
    _fly_setpoints(link, 6.0, send)
    assert not ap.armed and not ap.in_air
