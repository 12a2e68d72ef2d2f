"""Attitude and thrust set-points (SET_ATTITUDE_TARGET) flown by a point mass.

A multicopter accelerates where its thrust points: tilted by roll and pitch it accelerates
sideways by g * tan(angle) (a positive pitch raises the nose and flies backwards, a positive
roll flies right), and its collective thrust against the hover thrust MPC_THR_HOVER sets the
vertical acceleration (more climbs, less sinks). The autopilot integrates that acceleration
into the velocity the dynamics follow, so the vehicle stays within its speed limits.
"""

from __future__ import annotations

import math

from emulator.flight.offboard_frames import body_to_enu

__all__ = ["GRAVITY_M_S2", "attitude_acceleration_enu"]

GRAVITY_M_S2 = 9.80665
MAX_TILT_DEG = 60.0


def attitude_acceleration_enu(roll_deg: float, pitch_deg: float, yaw_deg: float,
                              thrust: float, hover_thrust: float
                              ) -> tuple[float, float, float]:
    """The acceleration (east, north, up; m/s^2) of attitude (deg) and normalised thrust."""
    roll = math.radians(max(-MAX_TILT_DEG, min(MAX_TILT_DEG, roll_deg)))
    pitch = math.radians(max(-MAX_TILT_DEG, min(MAX_TILT_DEG, pitch_deg)))
    forward = -GRAVITY_M_S2 * math.tan(pitch)
    right = GRAVITY_M_S2 * math.tan(roll)
    east, north = body_to_enu(yaw_deg, forward, right)
    up = GRAVITY_M_S2 * (max(thrust, 0.0) / hover_thrust - 1.0)
    return east, north, up
