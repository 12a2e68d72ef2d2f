"""HIGHRES_IMU of any set of vehicles, from the fleet's ground truth (a stream that is off
until a client sets its rate with MAV_CMD_SET_MESSAGE_INTERVAL, as on PX4's GCS link).

Body frame FRD, levelled (the point-mass model has no tilt of its own): the accelerometer
reads the specific force (acceleration minus gravity: -9.81 m/s^2 on z at rest), the gyro the
heading's rate over the last physics step, the magnetometer a fixed Earth field turned by the
heading, the barometer the standard atmosphere at the vehicle's altitude. One function serves
the batched stream and the single message, so both send the same numbers.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from emulator.flight.fleet_view import FleetView
from emulator.mavlink.codec import mavlink

__all__ = ["FIELDS_UPDATED", "highres_imu", "highres_imu_fields"]

GRAVITY_M_S2 = 9.80665
MAG_NORTH_GAUSS = 0.21  # the Earth field's horizontal (north) and downward components
MAG_DOWN_GAUSS = 0.43
SEA_LEVEL_HPA = 1013.25
FIELDS_UPDATED = 0x1FFF  # acc, gyro, mag (x, y, z each), pressures, altitude, temperature
IMU_ID = 0


def highres_imu_fields(fleet: FleetView, ks: np.ndarray) -> Sequence[object]:
    """The fields of HIGHRES_IMU, in the message's order, for vehicles ks."""
    dyn = fleet.dyn
    yaw = np.radians(dyn.yaw_deg[ks])
    cos, sin = np.cos(yaw), np.sin(yaw)
    a = dyn.accel_m_s2[ks]
    a_east, a_north, a_up = a[:, 0], a[:, 1], a[:, 2]
    forward = a_north * cos + a_east * sin
    right = -a_north * sin + a_east * cos
    down = -a_up - GRAVITY_M_S2
    steps = dyn.yaw_step_deg
    yaw_rate = (np.zeros(len(ks)) if steps is None
                else np.radians(steps[ks]) / fleet.dt_s)
    alt = fleet.world.origin.altitude_amsl_m + dyn.position_m[ks, 2]
    pressure = SEA_LEVEL_HPA * np.maximum(1.0 - 2.25577e-5 * alt, 0.0) ** 5.25588
    temperature = 15.0 - 0.0065 * alt
    zeros = np.zeros(len(ks))
    time_usec = int(fleet.now_s * 1e6)
    return (time_usec, forward, right, down, zeros, zeros, yaw_rate,
            MAG_NORTH_GAUSS * cos, -MAG_NORTH_GAUSS * sin, np.full(len(ks), MAG_DOWN_GAUSS),
            pressure, zeros, alt, temperature, FIELDS_UPDATED, IMU_ID)


def highres_imu(fleet: FleetView, k: int) -> mavlink.MAVLink_message:
    """HIGHRES_IMU of vehicle k."""
    fields = highres_imu_fields(fleet, np.array([k]))
    values = [v if isinstance(v, int) else float(np.asarray(v)[0]) for v in fields]
    return mavlink.MAVLink_highres_imu_message(*values)
