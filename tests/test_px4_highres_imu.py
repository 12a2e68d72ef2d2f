"""HIGHRES_IMU: off by default, streamed at the rate MAV_CMD_SET_MESSAGE_INTERVAL asks
(wall-clock rate), and its readings follow the ground truth (specific force at rest, the
heading's rate in a turn, the barometric altitude)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mavlink_vocabulary import MavCmd, MavResult, MessageId
from tests.memory_link import MemoryLink


def test_highres_imu_is_off_until_its_rate_is_set_then_follows_the_truth() -> None:
    link = MemoryLink(2)
    link.advance(2.0)
    assert not link.messages("HIGHRES_IMU")
    ack = link.command_long(1, MavCmd.SET_MESSAGE_INTERVAL, MessageId.HIGHRES_IMU, 20_000)
    assert ack.result == MavResult.ACCEPTED
    since = len(link.received)
    link.advance(2.0)
    imu = link.messages("HIGHRES_IMU", system=1, since=since)
    assert len(imu) == pytest.approx(100, abs=3)  # 50 Hz of wall-clock time
    assert not link.messages("HIGHRES_IMU", system=2, since=since)  # per vehicle
    m = imu[-1]
    assert (m.xacc, m.yacc) == pytest.approx((0.0, 0.0), abs=1e-6)
    assert m.zacc == pytest.approx(-9.80665, abs=1e-4)  # at rest: gravity only
    alt_amsl = link.fleet.world.origin.altitude_amsl_m
    assert m.pressure_alt == pytest.approx(alt_amsl, abs=0.01)
    assert m.abs_pressure == pytest.approx(1013.25 * (1 - 2.25577e-5 * alt_amsl) ** 5.25588,
                                           rel=1e-6)
    # a 90 degree turn at 30 deg/s: the gyro reads the heading's rate
    link.arm_and_take_off(1, 10.0)
    assert link.command_long(1, MavCmd.CONDITION_YAW, 90.0, 30.0, 1.0, 0.0).result == 0
    since = len(link.received)
    link.advance(1.5)
    gyro = np.array([m.zgyro for m in link.messages("HIGHRES_IMU", system=1, since=since)])
    assert np.median(gyro) == pytest.approx(math.radians(30.0), rel=0.01)
    # -1 turns it off again; REQUEST_MESSAGE sends one
    ack = link.command_long(1, MavCmd.SET_MESSAGE_INTERVAL, MessageId.HIGHRES_IMU, -1)
    assert ack.result == MavResult.ACCEPTED
    since = len(link.received)
    link.advance(1.0)
    assert not link.messages("HIGHRES_IMU", since=since)
    assert link.command_long(1, MavCmd.REQUEST_MESSAGE, MessageId.HIGHRES_IMU).result == 0
    assert len(link.messages("HIGHRES_IMU", since=since)) == 1
