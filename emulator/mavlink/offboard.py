"""Offboard set-points: SET_POSITION_TARGET_LOCAL_NED / GLOBAL_INT -> autopilot set-points.

MAVLink speaks NED (x north, y east, z down); the autopilot speaks ENU. Position targets
win over velocity targets when both are present, as in PX4. Malformed set-points (NaN,
unsupported frames, acceleration-only) are ignored, with one STATUSTEXT per kind of problem.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from emulator.flight.refusal import CommandRefused, Severity

if TYPE_CHECKING:
    from emulator.mavlink.vehicle_link import VehicleLink

__all__ = ["apply_global_setpoint", "apply_local_setpoint"]

_IGNORE_POSITION = 0x7
_IGNORE_VELOCITY = 0x38
_IGNORE_YAW = 0x400
FRAME_LOCAL_NED, FRAME_LOCAL_OFFSET_NED, FRAME_BODY_NED, FRAME_BODY_OFFSET_NED = 1, 7, 8, 9
FRAME_BODY_FRD = 12
_BODY_FRAMES = frozenset({FRAME_BODY_NED, FRAME_BODY_OFFSET_NED, FRAME_BODY_FRD})
_LOCAL_FRAMES = frozenset({FRAME_LOCAL_NED, FRAME_LOCAL_OFFSET_NED}) | _BODY_FRAMES
_GLOBAL_AMSL = frozenset({0, 5})
_GLOBAL_RELATIVE = frozenset({3, 6, 10, 11})


def _complain(link: VehicleLink, key: str, text: str) -> None:
    if key not in link.warned:
        link.warned.add(key)
        link.statustext(Severity.WARNING, text)


def _yaw_deg(m) -> float:
    if m.type_mask & _IGNORE_YAW or not math.isfinite(m.yaw):
        return math.nan
    return math.degrees(m.yaw) % 360.0


def _rotate_body(link: VehicleLink, forward: float, right: float) -> tuple[float, float]:
    """Body forward/right -> (east, north) using the vehicle's heading."""
    yaw = math.radians(float(link.ap.fleet.dyn.yaw_deg[link.k]))
    north = forward * math.cos(yaw) - right * math.sin(yaw)
    east = forward * math.sin(yaw) + right * math.cos(yaw)
    return east, north


def _position(link: VehicleLink, enu_m: tuple[float, float, float], yaw_deg: float) -> None:
    try:
        link.ap.offboard.setpoint("position", enu_m, yaw_deg, link.wall_now_s)
    except CommandRefused as refusal:
        _complain(link, "fence", str(refusal))


def apply_local_setpoint(link: VehicleLink, m) -> None:
    if m.coordinate_frame not in _LOCAL_FRAMES:
        _complain(link, f"frame{m.coordinate_frame}",
                  f"Offboard: frame {m.coordinate_frame} unsupported")
        return
    body = m.coordinate_frame in _BODY_FRAMES
    offset = m.coordinate_frame != FRAME_LOCAL_NED
    if not m.type_mask & _IGNORE_POSITION:
        values = (m.x, m.y, m.z)
        if not all(math.isfinite(v) for v in values):
            _complain(link, "nan", "Offboard: set-point with NaN ignored")
            return
        if body:
            east, north = _rotate_body(link, m.x, m.y)
        else:
            east, north = m.y, m.x
        up = -m.z
        if offset:
            x0, y0, z0 = link.ap.position_m
            east, north, up = east + x0, north + y0, up + z0
        _position(link, (east, north, up), _yaw_deg(m))
    elif not m.type_mask & _IGNORE_VELOCITY:
        values = (m.vx, m.vy, m.vz)
        if not all(math.isfinite(v) for v in values):
            _complain(link, "nan", "Offboard: set-point with NaN ignored")
            return
        east, north = _rotate_body(link, m.vx, m.vy) if body else (m.vy, m.vx)
        link.ap.offboard.setpoint("velocity", (east, north, -m.vz), _yaw_deg(m),
                                  link.wall_now_s)
    else:
        _complain(link, "mask", "Offboard: only position or velocity set-points supported")


def apply_global_setpoint(link: VehicleLink, m) -> None:
    frame = m.coordinate_frame
    if frame not in _GLOBAL_AMSL | _GLOBAL_RELATIVE:
        _complain(link, f"gframe{frame}", f"Offboard: frame {frame} unsupported")
        return
    ap = link.ap
    if not m.type_mask & _IGNORE_POSITION:
        lat, lon = m.lat_int * 1e-7, m.lon_int * 1e-7
        if not (math.isfinite(m.alt) and -90 <= lat <= 90 and -180 <= lon <= 180):
            _complain(link, "gbad", "Offboard: global set-point out of range ignored")
            return
        origin = ap.fleet.world.origin
        x, y, _ = origin.to_local(lat, lon, origin.altitude_amsl_m)
        z = m.alt - origin.altitude_amsl_m if frame in _GLOBAL_AMSL else ap.home_m[2] + m.alt
        _position(link, (x, y, z), _yaw_deg(m))
    elif not m.type_mask & _IGNORE_VELOCITY:
        if not all(math.isfinite(v) for v in (m.vx, m.vy, m.vz)):
            _complain(link, "nan", "Offboard: set-point with NaN ignored")
            return
        ap.offboard.setpoint("velocity", (m.vy, m.vx, -m.vz), _yaw_deg(m), link.wall_now_s)
    else:
        _complain(link, "mask", "Offboard: only position or velocity set-points supported")
