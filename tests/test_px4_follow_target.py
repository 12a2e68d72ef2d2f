"""PX4 conformance in memory: FOLLOW_TARGET fixes are followed in AUTO_FOLLOW_TARGET at the
FLW_TGT_* distance, angle and height (checked against the target's true path and the
recorder's trajectory); a lost target is held; bad fixes change nothing."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emulator.flight.follow_target import TARGET_TIMEOUT_S
from emulator.flight.modes import FlightMode
from mavlink_vocabulary import MavCmd, MavResult
from tests.memory_link import MemoryLink

FOLLOW = (1, 4, 8)  # DO_SET_MODE: custom, AUTO, FOLLOW_TARGET


class Target:
    """A target walking at a constant velocity (ENU m/s) from `start_m`, reported to the
    vehicle by FOLLOW_TARGET at 5 Hz, as a phone in a ground station would."""

    def __init__(self, link: MemoryLink, start_m: tuple[float, float],
                 velocity_m_s: tuple[float, float]) -> None:
        self.link, self.start_m, self.velocity_m_s = link, start_m, velocity_m_s
        self.t0_s = link.fleet.now_s

    def at(self, t_s: float) -> tuple[float, float]:
        dt = t_s - self.t0_s
        return (self.start_m[0] + self.velocity_m_s[0] * dt,
                self.start_m[1] + self.velocity_m_s[1] * dt)

    def send(self, *, vel: tuple[float, float, float] | None = None, alt_m: float = 0.0) -> int:
        link = self.link
        x, y = self.at(link.fleet.now_s)
        lat, lon, alt = link.fleet.world.origin.to_geodetic(x, y, alt_m)
        north, east = self.velocity_m_s[1], self.velocity_m_s[0]
        return link.send(link.mav.follow_target_encode(
            0, 1, round(lat * 1e7), round(lon * 1e7), alt, vel or (north, east, 0.0),
            (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0))

    def walk(self, seconds: float) -> None:
        for _ in range(round(seconds / 0.2)):
            self.send()
            self.link.advance(0.2)


def _followed(link: MemoryLink, target: Target, since_s: float) -> tuple[np.ndarray, ...]:
    rows = link.fleet.recorder.trajectory("d1")
    rows = rows[rows[:, 0] >= since_s]
    tx, ty = target.at(rows[:, 0])
    return rows, rows[:, 1] - tx, rows[:, 2] - ty


def test_a_walking_target_is_followed_behind_at_the_follow_distance_and_height() -> None:
    link = MemoryLink(1, telemetry=False)
    link.arm_and_take_off(1, 12.0)
    ap = link.fleet.autopilots[0]
    target = Target(link, (15.0, 5.0), (0.0, 2.0))  # walking north at 2 m/s
    target.send()
    assert link.command_long(1, MavCmd.DO_SET_MODE, *FOLLOW).result == MavResult.ACCEPTED
    assert ap.mode is FlightMode.FOLLOW_TARGET
    target.walk(20.0)
    t0 = link.fleet.now_s
    target.walk(20.0)
    rows, dx, dy = _followed(link, target, t0)
    distance, height = ap.params["FLW_TGT_DST"], ap.params["FLW_TGT_HT"]  # 8 m, 8 m
    assert dx == pytest.approx(np.zeros_like(dx), abs=0.1)  # behind: south of it
    assert dy == pytest.approx(np.full_like(dy, -distance), abs=0.1)
    assert rows[:, 3] == pytest.approx(np.full_like(dy, height), abs=0.05)
    heading = (rows[:, 4] + 180.0) % 360.0 - 180.0
    assert heading == pytest.approx(np.zeros_like(heading), abs=1.0)  # facing the target


def test_follow_parameters_set_the_side_distance_and_height() -> None:
    link = MemoryLink(1, telemetry=False)
    link.arm_and_take_off(1, 10.0)
    ap = link.fleet.autopilots[0]
    for name, value in (("FLW_TGT_FA", 90.0), ("FLW_TGT_DST", 15.0), ("FLW_TGT_HT", 20.0)):
        ap.set_param(name, value)
    target = Target(link, (-10.0, 0.0), (1.5, 0.0))  # walking east
    target.send()
    assert link.command_long(1, MavCmd.DO_SET_MODE, *FOLLOW).result == MavResult.ACCEPTED
    target.walk(40.0)
    t0 = link.fleet.now_s
    target.walk(10.0)
    rows, dx, dy = _followed(link, target, t0)
    # 90 deg: to the target's right (south of an eastbound target), 15 m off, 20 m up
    assert dx == pytest.approx(np.zeros_like(dx), abs=0.1)
    assert dy == pytest.approx(np.full_like(dy, -15.0), abs=0.1)
    assert rows[:, 3] == pytest.approx(np.full_like(dy, 20.0), abs=0.05)
    # FLW_TGT_ALT_M 2: the height is above the target's altitude
    ap.set_param("FLW_TGT_ALT_M", 2)
    for _ in range(50):
        target.send(alt_m=5.0)
        link.advance(0.2)
    assert ap.position_m[2] == pytest.approx(25.0, abs=0.05)


def test_a_new_follow_angle_is_reached_circling_at_flw_tgt_max_vel() -> None:
    link = MemoryLink(1, telemetry=False)
    link.arm_and_take_off(1, 10.0)
    ap = link.fleet.autopilots[0]
    target = Target(link, (0.0, 10.0), (0.0, 1.0))
    target.send()
    assert link.command_long(1, MavCmd.DO_SET_MODE, *FOLLOW).result == MavResult.ACCEPTED
    target.walk(20.0)
    ap.set_param("FLW_TGT_FA", 0.0)  # to the front: half a circle of radius 8 m at 5 m/s
    t0 = link.fleet.now_s
    target.walk(15.0)
    rows, dx, dy = _followed(link, target, t0)
    angle = np.degrees(np.arctan2(dx, dy)) % 360.0  # bearing from the target
    swing_s = math.pi * ap.params["FLW_TGT_DST"] / ap.params["FLW_TGT_MAX_VEL"]
    in_front = rows[np.abs((angle + 180.0) % 360.0 - 180.0) < 2.0, 0]
    # no faster than the follow point circles; late by the time speeding up to it takes
    assert in_front.size and swing_s <= in_front[0] - t0 <= swing_s + 2.5
    assert (dx[-1], dy[-1]) == pytest.approx((0.0, 8.0), abs=0.1)


def test_a_lost_target_is_held_where_it_was_last_estimated() -> None:
    link = MemoryLink(1, telemetry=False)
    link.arm_and_take_off(1, 10.0)
    ap = link.fleet.autopilots[0]
    target = Target(link, (0.0, 10.0), (0.0, 2.0))
    target.send()
    assert link.command_long(1, MavCmd.DO_SET_MODE, *FOLLOW).result == MavResult.ACCEPTED
    target.walk(15.0)
    since = len(link.received)
    link.advance(TARGET_TIMEOUT_S + 0.1)  # no fix: extrapolated, then lost
    assert "Follow target lost: holding" in [m.text for m in
                                             link.messages("STATUSTEXT", since=since)]
    [lost] = link.fleet.recorder.events("d1", kinds="follow_target_lost")
    last = lost.data["target_m"]  # the extrapolation, right to the moment it was lost
    assert last[:2] == pytest.approx(target.at(lost.t_s), abs=0.05)
    link.advance(10.0)
    x, y, _ = ap.position_m
    assert (x, y) == pytest.approx((last[0], last[1] - 8.0), abs=0.05)
    assert link.fleet.dyn.speed_m_s(0) < 0.05 and ap.mode is FlightMode.FOLLOW_TARGET
    target.walk(15.0)  # fixes again: followed again, behind
    assert "Follow target regained" in [m.text for m in link.messages("STATUSTEXT")]
    x, y, _ = ap.position_m
    tx, ty = target.at(link.fleet.now_s)
    assert (x - tx, y - ty) == pytest.approx((0.0, -8.0), abs=0.1)


def test_follow_refusals_and_bad_fixes_change_nothing() -> None:
    link = MemoryLink(1, telemetry=False)
    ap = link.fleet.autopilots[0]
    ack = link.command_long(1, MavCmd.DO_SET_MODE, *FOLLOW)
    assert ack.result == MavResult.DENIED and ap.mode is FlightMode.HOLD  # on the ground
    link.arm_and_take_off(1, 10.0)
    target = Target(link, (0.0, 10.0), (0.0, 0.0))
    since = target.send(vel=(500.0, 0.0, 0.0))
    link.send(link.mav.follow_target_encode(0, 1, 91 * 10**7, 0, 0.0, (0.0, 0.0, 0.0),
                                            (0.0,) * 3, (1.0, 0.0, 0.0, 0.0), (0.0,) * 3,
                                            (0.0,) * 3, 0))
    assert ap.follow.fix is None
    texts = [m.text for m in link.messages("STATUSTEXT", since=since)]
    assert texts == ["Follow target: velocity out of range ignored",
                     "Follow target: position out of range ignored"]
    # entering without a target: it holds where it is until one comes
    here = ap.position_m
    assert link.command_long(1, MavCmd.DO_SET_MODE, *FOLLOW).result == MavResult.ACCEPTED
    link.advance(3.0)
    assert math.dist(ap.position_m, here) < 0.05
    target.send(vel=(math.nan, math.nan, math.nan))  # NaN velocity reads as standing still
    link.advance(10.0)
    assert math.dist(ap.position_m[:2], (0.0, 2.0)) == pytest.approx(0.0, abs=0.1)
