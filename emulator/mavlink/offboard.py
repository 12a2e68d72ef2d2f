"""Offboard set-points: SET_POSITION_TARGET_LOCAL_NED / GLOBAL_INT -> autopilot set-points.

MAVLink speaks NED (x north, y east, z down) about the vehicle's local origin (its own EKF
origin by default, as PX4; see `Fleet.local_origin_m`); the autopilot speaks ENU about the
session origin. Position targets win over velocity targets when both are present, as in PX4;
a yaw wins over a yaw rate. A body-frame velocity is handed over as forward/right/up and
turned with the heading as the vehicle flies. Malformed set-points (NaN,
unsupported frames, acceleration-only) are ignored: each function returns the problem as a
`Complaint` (a kind and a text), which the vehicle link reports once per kind.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from emulator.flight.autopilot import Autopilot
from emulator.flight.offboard_frames import body_to_enu
from emulator.flight.refusal import CommandRefused
from mavlink_vocabulary import MavFrame, MessageId
from mavlink_vocabulary import PositionTargetTypemask as Mask

__all__ = ["SETPOINT_APPLIERS", "Complaint", "apply_attitude_target", "apply_global_setpoint",
           "apply_local_setpoint"]

# plain ints: masks are tested for every set-point
_IGNORE_POSITION = int(Mask.X_IGNORE | Mask.Y_IGNORE | Mask.Z_IGNORE)
_IGNORE_VELOCITY = int(Mask.VX_IGNORE | Mask.VY_IGNORE | Mask.VZ_IGNORE)
_IGNORE_YAW = int(Mask.YAW_IGNORE)
_IGNORE_YAW_RATE = int(Mask.YAW_RATE_IGNORE)
_BODY_FRAMES = frozenset({MavFrame.BODY_NED, MavFrame.BODY_OFFSET_NED, MavFrame.BODY_FRD})
_LOCAL_FRAMES = frozenset({MavFrame.LOCAL_NED, MavFrame.LOCAL_OFFSET_NED}) | _BODY_FRAMES
_GLOBAL_AMSL = frozenset({MavFrame.GLOBAL, MavFrame.GLOBAL_INT})
_GLOBAL_RELATIVE = frozenset({MavFrame.GLOBAL_RELATIVE_ALT, MavFrame.GLOBAL_RELATIVE_ALT_INT,
                              MavFrame.GLOBAL_TERRAIN_ALT, MavFrame.GLOBAL_TERRAIN_ALT_INT})


class Complaint(NamedTuple):
    key: str  # the kind of problem: reported once per vehicle
    text: str


_NAN = Complaint("nan", "Offboard: set-point with NaN ignored")
_MASK = Complaint("mask", "Offboard: only position or velocity set-points supported")


def _yaw_deg(m) -> float:
    if m.type_mask & _IGNORE_YAW or not math.isfinite(m.yaw):
        return math.nan
    return math.degrees(m.yaw) % 360.0


def _yaw_rate_deg_s(m) -> float:
    if m.type_mask & _IGNORE_YAW_RATE or not math.isfinite(m.yaw_rate):
        return math.nan
    return math.degrees(m.yaw_rate)


def _rotate_body(ap: Autopilot, forward: float, right: float) -> tuple[float, float]:
    """Body forward/right -> (east, north) using the vehicle's heading."""
    return body_to_enu(float(ap.fleet.dyn.yaw_deg[ap.k]), forward, right)


def _position(ap: Autopilot, enu_m: tuple[float, float, float], yaw_deg: float,
              wall_now_s: float) -> Complaint | None:
    try:
        ap.offboard.setpoint("position", enu_m, yaw_deg, wall_now_s)
    except CommandRefused as refusal:
        return Complaint("fence", str(refusal))
    return None


def apply_local_setpoint(ap: Autopilot, m, wall_now_s: float) -> Complaint | None:
    if m.coordinate_frame not in _LOCAL_FRAMES:
        return Complaint(f"frame{m.coordinate_frame}",
                         f"Offboard: frame {m.coordinate_frame} unsupported")
    body = m.coordinate_frame in _BODY_FRAMES
    offset = m.coordinate_frame != MavFrame.LOCAL_NED
    if not m.type_mask & _IGNORE_POSITION:
        if not all(math.isfinite(v) for v in (m.x, m.y, m.z)):
            return _NAN
        if body:
            east, north = _rotate_body(ap, m.x, m.y)
        else:
            east, north = m.y, m.x
        up = -m.z
        x0, y0, z0 = ap.position_m if offset else ap.fleet.local_origin(ap.k)
        return _position(ap, (east + x0, north + y0, up + z0), _yaw_deg(m), wall_now_s)
    if not m.type_mask & _IGNORE_VELOCITY:
        if not all(math.isfinite(v) for v in (m.vx, m.vy, m.vz)):
            return _NAN
        vector = (m.vx, m.vy, -m.vz) if body else (m.vy, m.vx, -m.vz)
        ap.offboard.setpoint("velocity", vector, _yaw_deg(m), wall_now_s,
                             yaw_rate_deg_s=_yaw_rate_deg_s(m), body=body)
        return None
    return _MASK


def apply_global_setpoint(ap: Autopilot, m, wall_now_s: float) -> Complaint | None:
    frame = m.coordinate_frame
    if frame not in _GLOBAL_AMSL | _GLOBAL_RELATIVE:
        return Complaint(f"gframe{frame}", f"Offboard: frame {frame} unsupported")
    if not m.type_mask & _IGNORE_POSITION:
        lat, lon = m.lat_int * 1e-7, m.lon_int * 1e-7
        if not (math.isfinite(m.alt) and -90 <= lat <= 90 and -180 <= lon <= 180):
            return Complaint("gbad", "Offboard: global set-point out of range ignored")
        origin = ap.fleet.world.origin
        x, y, _ = origin.to_local(lat, lon, origin.altitude_amsl_m)
        z = m.alt - origin.altitude_amsl_m if frame in _GLOBAL_AMSL else ap.home_m[2] + m.alt
        return _position(ap, (x, y, z), _yaw_deg(m), wall_now_s)
    if not m.type_mask & _IGNORE_VELOCITY:
        if not all(math.isfinite(v) for v in (m.vx, m.vy, m.vz)):
            return _NAN
        ap.offboard.setpoint("velocity", (m.vy, m.vx, -m.vz), _yaw_deg(m), wall_now_s,
                             yaw_rate_deg_s=_yaw_rate_deg_s(m))
        return None
    return _MASK


# SET_ATTITUDE_TARGET.type_mask bits
_IGNORE_BODY_YAW_RATE = 4
_IGNORE_THRUST = 64
_IGNORE_ATTITUDE = 128


def _euler_deg(q: list[float]) -> tuple[float, float, float]:
    """Roll, pitch, yaw (deg, yaw 0..360 from north) of a quaternion w, x, y, z (NED)."""
    w, x, y, z = q
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return math.degrees(roll), math.degrees(pitch), math.degrees(yaw) % 360.0


def apply_attitude_target(ap: Autopilot, m, wall_now_s: float) -> Complaint | None:
    """SET_ATTITUDE_TARGET: attitude (quaternion) and thrust; without an attitude, level
    flight turning at the body yaw rate."""
    mask = m.type_mask
    thrust = ap.params["MPC_THR_HOVER"] if mask & _IGNORE_THRUST else m.thrust
    if not math.isfinite(thrust):
        return _NAN
    yaw_rate = math.nan
    if mask & _IGNORE_ATTITUDE:
        roll = pitch = 0.0
        yaw = math.nan
        if not mask & _IGNORE_BODY_YAW_RATE and math.isfinite(m.body_yaw_rate):
            yaw_rate = math.degrees(m.body_yaw_rate)
    else:
        q = [float(v) for v in m.q]
        norm = math.sqrt(sum(v * v for v in q))
        if not (math.isfinite(norm) and norm > 1e-6):
            return Complaint("quaternion", "Offboard: attitude quaternion invalid")
        roll, pitch, yaw = _euler_deg([v / norm for v in q])
    ap.offboard.setpoint("attitude", (roll, pitch, min(max(thrust, 0.0), 1.0)), yaw,
                         wall_now_s, yaw_rate_deg_s=yaw_rate)
    return None


SETPOINT_APPLIERS = {
    MessageId.SET_POSITION_TARGET_LOCAL_NED: apply_local_setpoint,
    MessageId.SET_POSITION_TARGET_GLOBAL_INT: apply_global_setpoint,
    MessageId.SET_ATTITUDE_TARGET: apply_attitude_target,
}
