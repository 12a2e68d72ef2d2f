"""PX4 conformance in memory: MAV_CMD_DO_ORBIT flies a circle of the asked radius, speed,
direction and yaw behaviour (checked against the recorder's trajectory); bad ones change
nothing."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emulator.flight.modes import FlightMode
from mavlink_vocabulary import MavCmd, MavResult
from tests.memory_link import MemoryLink


def _orbit_rows(link: MemoryLink, seconds: float) -> np.ndarray:
    t0 = link.fleet.now_s
    link.advance(seconds)
    rows = link.fleet.recorder.trajectory("d1")
    return rows[rows[:, 0] >= t0]


def test_do_orbit_flies_a_circle_of_the_asked_radius_and_speed() -> None:
    link = MemoryLink(1, telemetry=False)
    link.arm_and_take_off(1, 10.0)
    ap = link.fleet.autopilots[0]
    origin = link.fleet.world.origin
    cx, cy = 30.0, 20.0
    lat, lon, _ = origin.to_geodetic(cx, cy, 0.0)
    alt_amsl = origin.altitude_amsl_m + 15.0
    # radius 12 m clockwise, 4 m/s, front to the centre
    ack = link.command_long(1, MavCmd.DO_ORBIT, 12.0, 4.0, 0.0, math.nan, lat, lon, alt_amsl)
    assert ack.result == MavResult.ACCEPTED
    assert ap.mode is FlightMode.ORBIT
    link.advance(25.0)  # reach the circle
    rows = _orbit_rows(link, 20.0)
    rel = rows[:, 1:3] - (cx, cy)
    r = np.hypot(rel[:, 0], rel[:, 1])
    assert r == pytest.approx(np.full(r.shape, 12.0), abs=0.3)
    assert rows[:, 3] == pytest.approx(np.full(r.shape, 15.0), abs=0.2)
    angle = np.unwrap(np.arctan2(rel[:, 1], rel[:, 0]))
    rate = (angle[-1] - angle[0]) / (rows[-1, 0] - rows[0, 0])
    assert rate == pytest.approx(-4.0 / 12.0, rel=0.03)  # clockwise: the angle decreases
    # the front points at the centre
    bearing = np.degrees(np.arctan2(-rel[:, 0], -rel[:, 1])) % 360.0
    off = (rows[:, 4] - bearing + 180.0) % 360.0 - 180.0
    assert np.abs(off).max() < 3.0
    # a negative radius orbits counter-clockwise; HOLD ends the orbit
    lat2, lon2, _ = origin.to_geodetic(cx, cy, 0.0)
    assert link.command_long(1, MavCmd.DO_ORBIT, -12.0, 4.0, 0.0, math.nan, lat2, lon2,
                             alt_amsl).result == MavResult.ACCEPTED
    link.advance(5.0)
    rows = _orbit_rows(link, 10.0)
    rel = rows[:, 1:3] - (cx, cy)
    angle = np.unwrap(np.arctan2(rel[:, 1], rel[:, 0]))
    assert (angle[-1] - angle[0]) / (rows[-1, 0] - rows[0, 0]) == pytest.approx(4.0 / 12.0,
                                                                               rel=0.05)
    assert link.command_long(1, MavCmd.DO_SET_MODE, 1, 4, 3).result == MavResult.ACCEPTED
    link.advance(5.0)
    assert ap.mode is FlightMode.HOLD
    assert link.fleet.dyn.speed_m_s(0) < 0.05


def test_do_orbit_refusals_change_nothing() -> None:
    link = MemoryLink(1, telemetry=False)
    ap = link.fleet.autopilots[0]
    nan = math.nan
    ack = link.command_long(1, MavCmd.DO_ORBIT, 10.0, 2.0, 0.0, nan, nan, nan, nan)
    assert ack.result == MavResult.DENIED  # on the ground
    link.arm_and_take_off(1)
    since = len(link.received)
    for params in [(0.5, 2.0, 0.0), (5000.0, 2.0, 0.0), (10.0, 2.0, 9.0)]:
        ack = link.command_long(1, MavCmd.DO_ORBIT, *params, nan, nan, nan, nan)
        assert ack.result == MavResult.DENIED, params
    texts = [m.text for m in link.messages("STATUSTEXT", since=since)]
    assert any("radius" in t for t in texts) and any("yaw behaviour" in t for t in texts)
    assert ap.mode is FlightMode.HOLD
    # all unset: around where it is, at the default radius
    ack = link.command_long(1, MavCmd.DO_ORBIT, nan, nan, nan, nan, nan, nan, nan)
    assert ack.result == MavResult.ACCEPTED and ap.mode is FlightMode.ORBIT
