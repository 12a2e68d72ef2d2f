"""The flight envelope a vehicle's parameters allow: speeds, rates, geofence and home.

Every check raises :class:`CommandRefused` with a sentence naming the value and the allowed
range (short enough for one 50-character STATUSTEXT), before anything changes. Lower bounds
come from the parameter definitions (the smallest value the airframe can be configured to
fly at), upper bounds from the values now in force, so nothing a client sends can set a
speed the vehicle could never complete a flight at, or put home where the geofence would
strand the vehicle.
"""

from __future__ import annotations

import math
from enum import IntEnum

from emulator.flight.params import ParamStore
from emulator.flight.refusal import CommandRefused

__all__ = [
    "HOME_BELOW_GROUND_M",
    "SpeedKind",
    "check_altitude",
    "check_distance_from_home",
    "check_home",
    "check_speed",
    "check_target",
    "check_yaw_rate",
    "speed_range_m_s",
]

Vec3 = tuple[float, float, float]
HOME_BELOW_GROUND_M = 0.5  # an AMSL home this far below the ground counts as on it


class SpeedKind(IntEnum):
    """MAV_CMD_DO_CHANGE_SPEED param1 (SPEED_TYPE)."""

    AIRSPEED = 0
    GROUND = 1
    CLIMB = 2
    DESCENT = 3


# (parameter whose range minimum is the floor, parameter whose value is the ceiling)
_SPEED_BOUNDS: dict[SpeedKind, tuple[str, str]] = {
    SpeedKind.AIRSPEED: ("MPC_XY_CRUISE", "MPC_XY_VEL_MAX"),
    SpeedKind.GROUND: ("MPC_XY_CRUISE", "MPC_XY_VEL_MAX"),
    SpeedKind.CLIMB: ("MPC_Z_VEL_MAX_UP", "MPC_Z_VEL_MAX_UP"),
    SpeedKind.DESCENT: ("MPC_Z_VEL_MAX_DN", "MPC_Z_VEL_MAX_DN"),
}
_SPEED_LABELS = {
    SpeedKind.AIRSPEED: "airspeed", SpeedKind.GROUND: "speed",
    SpeedKind.CLIMB: "climb", SpeedKind.DESCENT: "descent",
}


def _metres(value: float) -> str:
    return f"{value:.0f}" if abs(value) < 1e6 else f"{value:.3g}"


def speed_range_m_s(params: ParamStore, kind: SpeedKind) -> tuple[float, float]:
    """The [lowest, highest] speed of `kind` the vehicle accepts now."""
    floor_name, ceiling_name = _SPEED_BOUNDS[kind]
    return ParamStore.definition(floor_name).minimum, params[ceiling_name]


def check_speed(params: ParamStore, kind: SpeedKind, speed_m_s: float, what: str) -> float:
    """Return speed_m_s if it lies in the allowed range; raise CommandRefused otherwise."""
    lo, hi = speed_range_m_s(params, kind)
    if not (math.isfinite(speed_m_s) and lo <= speed_m_s <= hi):
        raise CommandRefused(
            f"{what}: {_SPEED_LABELS[kind]} {speed_m_s:.3g} m/s not in [{lo:.3g}, {hi:.3g}]"
        )
    return speed_m_s


def check_yaw_rate(params: ParamStore, rate_deg_s: float, what: str) -> None:
    """A requested yaw rate (> 0) must be at least MPC_YAWRAUTO_MAX's range minimum."""
    lo = ParamStore.definition("MPC_YAWRAUTO_MAX").minimum
    if not (math.isfinite(rate_deg_s) and rate_deg_s >= lo):
        raise CommandRefused(f"{what}: yaw rate {rate_deg_s:.3g} deg/s below {lo:g}")


def check_altitude(params: ParamStore, home_m: Vec3, z_m: float, what: str) -> None:
    """A target altitude must be a number, above ground and below the ceiling."""
    ceiling = params["GF_MAX_VER_DIST"]
    if not math.isfinite(z_m):
        raise CommandRefused(f"{what} refused: altitude is not a number")
    if z_m < 0.0:
        raise CommandRefused(f"{what} refused: altitude {z_m:.1f} m is below ground")
    if z_m - home_m[2] > ceiling:
        raise CommandRefused(
            f"{what} refused: altitude {z_m - home_m[2]:.0f} m exceeds ceiling "
            f"{ceiling:.0f} m"
        )


def check_distance_from_home(params: ParamStore, home_m: Vec3, x_m: float, y_m: float,
                             what: str) -> None:
    """A point must lie within GF_MAX_HOR_DIST of home."""
    limit = params["GF_MAX_HOR_DIST"]
    dist = math.hypot(x_m - home_m[0], y_m - home_m[1])
    if not dist <= limit:
        raise CommandRefused(
            f"{what} refused: {dist:.0f} m from home exceeds geofence {limit:.0f} m"
        )


def check_target(params: ParamStore, home_m: Vec3, target_m: Vec3, what: str) -> None:
    """Refuse a destination outside the geofence (ceiling, distance from home)."""
    check_altitude(params, home_m, target_m[2], what)
    check_distance_from_home(params, home_m, target_m[0], target_m[1], what)


def check_home(params: ParamStore, home_m: Vec3, vehicle_m: Vec3) -> Vec3:
    """Validate a new home; returns it with a slightly negative altitude put on the ground.

    Home must lie within SIM_HOME_MAXDIST of the session origin (local (0, 0)), between
    the ground and the ceiling (GF_MAX_VER_DIST) in height, and within the geofence radius
    (GF_MAX_HOR_DIST) of the vehicle, which would otherwise be refused every destination
    on its side of it.
    """
    what = "Set home"
    if not all(math.isfinite(v) for v in home_m):
        raise CommandRefused(f"{what}: coordinates must be numbers")
    x, y, z = (float(v) for v in home_m)
    max_origin_m = params["SIM_HOME_MAXDIST"]
    from_origin_m = math.hypot(x, y)
    if from_origin_m > max_origin_m:
        raise CommandRefused(
            f"{what}: {_metres(from_origin_m)} m from origin, limit {max_origin_m:.0f} m"
        )
    ceiling = params["GF_MAX_VER_DIST"]
    if not -HOME_BELOW_GROUND_M <= z <= ceiling:
        raise CommandRefused(f"{what}: altitude {_metres(z)} m not in [0, {ceiling:.0f}] m")
    fence_m = params["GF_MAX_HOR_DIST"]
    from_vehicle_m = math.hypot(x - vehicle_m[0], y - vehicle_m[1])
    if from_vehicle_m > fence_m:
        raise CommandRefused(
            f"{what}: {_metres(from_vehicle_m)} m from vehicle, fence {fence_m:.0f} m"
        )
    return x, y, max(z, 0.0)
