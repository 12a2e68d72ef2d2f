"""SET_ATTITUDE_TARGET offboard, in memory: thrust above hover climbs, a pitch forward flies
forward, a roll flies sideways, thrust below hover sinks to a detected landing; checked
against the ground truth."""

from __future__ import annotations

import math

import pytest

from emulator.flight.modes import FlightMode
from mavlink_vocabulary import MavCmd
from tests.memory_link import MemoryLink

ATTITUDE_AND_THRUST = 0b0000_0111  # body rates ignored


def _quaternion(roll_deg: float, pitch_deg: float, yaw_deg: float) -> list[float]:
    r, p, y = (math.radians(a) / 2.0 for a in (roll_deg, pitch_deg, yaw_deg))
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), \
        math.cos(y), math.sin(y)
    return [cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy]


def _fly(link: MemoryLink, seconds: float, roll: float, pitch: float, yaw: float,
         thrust: float) -> None:
    for _ in range(round(seconds / 0.1)):
        link.send(link.mav.set_attitude_target_encode(
            0, 1, 1, ATTITUDE_AND_THRUST, _quaternion(roll, pitch, yaw), 0, 0, 0, thrust))
        link.advance(0.1)


def test_attitude_and_thrust_set_points_fly_the_vehicle() -> None:
    link = MemoryLink(1, telemetry=False)
    ap = link.fleet.autopilots[0]
    assert link.command_long(1, MavCmd.COMPONENT_ARM_DISARM, 1.0).result == 0
    _fly(link, 0.3, 0.0, 0.0, 0.0, 0.6)
    assert link.command_long(1, MavCmd.DO_SET_MODE, 1, 6, 0).result == 0
    assert ap.mode is FlightMode.OFFBOARD
    _fly(link, 3.0, 0.0, 0.0, 0.0, 0.6)  # thrust above hover (0.5): it takes off and climbs
    assert ap.in_air and ap.position_m[2] > 3.0
    x0, y0, _ = ap.position_m
    _fly(link, 2.0, 0.0, 0.0, 0.0, 0.5)  # hover thrust: the climb rate stays
    _fly(link, 3.0, 0.0, -10.0, 0.0, 0.5)  # nose down, heading north: flies north
    x1, y1, _ = ap.position_m
    assert y1 - y0 > 3.0 and abs(x1 - x0) < 0.5
    vy0 = float(link.fleet.dyn.velocity_m_s[0][1])
    _fly(link, 3.0, 10.0, 0.0, 90.0, 0.5)  # heading east, rolled right: accelerates south
    assert float(link.fleet.dyn.yaw_deg[0]) == pytest.approx(90.0, abs=1.0)
    vx, vy, _ = link.fleet.dyn.velocity_m_s[0]
    assert vy - vy0 < -3.0 and abs(vx) < 0.5
    _fly(link, 30.0, 0.0, 0.0, 90.0, 0.3)  # below hover: it sinks and lands
    kinds = [e.kind for e in link.fleet.recorder.events("d1")]
    assert "landed" in kinds and not ap.in_air
    link.advance(3.0)
    assert not ap.armed  # COM_DISARM_LAND after the landing


def test_bad_attitude_set_points_are_ignored_and_reported_once() -> None:
    link = MemoryLink(1, telemetry=False)
    since = len(link.received)
    for _ in range(2):
        link.send(link.mav.set_attitude_target_encode(0, 1, 1, ATTITUDE_AND_THRUST,
                                                      [0.0, 0.0, 0.0, 0.0], 0, 0, 0, 0.5))
        link.send(link.mav.set_attitude_target_encode(0, 1, 1, ATTITUDE_AND_THRUST,
                                                      [1.0, 0.0, 0.0, 0.0], 0, 0, 0, math.nan))
    texts = [m.text for m in link.messages("STATUSTEXT", since=since)]
    assert texts == ["Offboard: attitude quaternion invalid",
                     "Offboard: set-point with NaN ignored"]
    # with no valid set-point, OFFBOARD is refused
    assert link.command_long(1, MavCmd.DO_SET_MODE, 1, 6, 0).result == 2
