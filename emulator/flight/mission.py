"""Mission items as a vehicle stores them, their validation and their local targets."""

from __future__ import annotations

import math
from dataclasses import dataclass

from emulator.flight.limits import SpeedKind, check_speed, check_yaw_rate
from emulator.flight.params import ParamStore
from emulator.flight.refusal import CommandRefused
from emulator.geo import GeoOrigin
from mavlink_vocabulary import MavCmd, MavFrame, MavMissionResult

__all__ = [
    "NAV_COMMANDS",
    "PAYLOAD_COMMANDS",
    "SUPPORTED_COMMANDS",
    "Cmd",
    "MissionItem",
    "MissionResult",
    "validate_item",
    "validate_item_limits",
]


Cmd = MavCmd  # the MAV_CMD ids; SUPPORTED_COMMANDS are those the mission executor flies
MissionResult = MavMissionResult  # a MISSION_ACK's type


NAV_COMMANDS = frozenset(
    {Cmd.NAV_WAYPOINT, Cmd.NAV_LOITER_UNLIM, Cmd.NAV_LOITER_TIME, Cmd.NAV_LAND, Cmd.NAV_TAKEOFF}
)
# Gimbal, region-of-interest and camera items PX4 accepts in a plan (QGroundControl's and
# MAVSDK's mission plugins write them): stored and passed over in flight, since the vehicle
# carries no gimbal and its camera takes photos only when told to.
PAYLOAD_COMMANDS = frozenset({
    Cmd.DO_SET_ROI_LOCATION, Cmd.DO_SET_ROI_WPNEXT_OFFSET, Cmd.DO_SET_ROI_NONE,
    Cmd.DO_DIGICAM_CONTROL, Cmd.DO_MOUNT_CONFIGURE, Cmd.DO_MOUNT_CONTROL,
    Cmd.DO_SET_CAM_TRIGG_DIST, Cmd.DO_SET_CAM_TRIGG_INTERVAL, Cmd.DO_GIMBAL_MANAGER_PITCHYAW,
    Cmd.DO_GIMBAL_MANAGER_CONFIGURE, Cmd.IMAGE_STOP_CAPTURE, Cmd.DO_TRIGGER_CONTROL,
    Cmd.VIDEO_START_CAPTURE, Cmd.VIDEO_STOP_CAPTURE, Cmd.SET_CAMERA_MODE, Cmd.SET_CAMERA_ZOOM,
    Cmd.SET_CAMERA_FOCUS,
})
SUPPORTED_COMMANDS = NAV_COMMANDS | PAYLOAD_COMMANDS | {
    Cmd.NAV_RETURN_TO_LAUNCH, Cmd.NAV_DELAY, Cmd.CONDITION_YAW, Cmd.DO_CHANGE_SPEED,
    Cmd.IMAGE_START_CAPTURE,
}
FRAMES_AMSL = frozenset({MavFrame.GLOBAL, MavFrame.GLOBAL_INT})
FRAMES_RELATIVE = frozenset({MavFrame.GLOBAL_RELATIVE_ALT, MavFrame.GLOBAL_RELATIVE_ALT_INT})
MAX_ITEMS = 1000


@dataclass(frozen=True, slots=True)
class MissionItem:
    """One MISSION_ITEM_INT as uploaded; x/y are degrees * 1e7, z metres in `frame`."""

    seq: int
    frame: int
    command: int
    param1: float = 0.0
    param2: float = 0.0
    param3: float = 0.0
    param4: float = math.nan
    x: int = 0
    y: int = 0
    z: float = 0.0
    autocontinue: int = 1

    @property
    def is_nav(self) -> bool:
        return self.command in NAV_COMMANDS

    @property
    def uses_current_position(self) -> bool:
        """Take-off, land and loiter items with lat = lon = 0 mean 'where the vehicle is'."""
        return self.x == 0 and self.y == 0 and self.command != Cmd.NAV_WAYPOINT

    def local_target_m(
        self, origin: GeoOrigin, home_m: tuple[float, float, float],
        current_m: tuple[float, float, float],
    ) -> tuple[float, float, float]:
        """Where a positional item sends the vehicle, in local ENU metres."""
        if self.uses_current_position:
            x_m, y_m = current_m[0], current_m[1]
        else:
            x_m, y_m, _ = origin.to_local(self.x * 1e-7, self.y * 1e-7, origin.altitude_amsl_m)
        if not math.isfinite(self.z):
            z_m = current_m[2]
        elif self.frame in FRAMES_AMSL:
            z_m = self.z - origin.altitude_amsl_m
        else:
            z_m = home_m[2] + self.z
        return x_m, y_m, z_m


def validate_item(
    item: MissionItem, origin: GeoOrigin, home_m: tuple[float, float, float],
    ceiling_m: float, max_distance_m: float,
) -> tuple[int, str]:
    """Check one item before it is stored: (MAV_MISSION_RESULT, reason)."""
    where = f"mission item {item.seq}"
    if item.command not in SUPPORTED_COMMANDS:
        return MissionResult.UNSUPPORTED, f"{where}: command {item.command} unsupported"
    for name in ("param1", "param2", "param3"):
        value = getattr(item, name)
        if math.isinf(value):
            return MissionResult.INVALID_PARAM1, f"{where}: {name} is infinite"
    if not item.is_nav:
        if item.command == Cmd.NAV_DELAY and not (math.isfinite(item.param1) and item.param1 >= 0):
            return MissionResult.INVALID_PARAM1, f"{where}: delay must be >= 0 s"
        if item.command == Cmd.DO_CHANGE_SPEED and not math.isfinite(item.param2):
            return MissionResult.INVALID_PARAM1, f"{where}: speed must be a number"
        if item.command == Cmd.CONDITION_YAW and not math.isfinite(item.param1):
            return MissionResult.INVALID_PARAM1, f"{where}: yaw angle must be a number"
        return MissionResult.ACCEPTED, ""
    if item.frame not in FRAMES_AMSL | FRAMES_RELATIVE:
        return MissionResult.UNSUPPORTED_FRAME, f"{where}: frame {item.frame} unsupported"
    if not -900_000_000 <= item.x <= 900_000_000:
        return MissionResult.INVALID_PARAM5_X, f"{where}: latitude out of range"
    if not -1_800_000_000 <= item.y <= 1_800_000_000:
        return MissionResult.INVALID_PARAM6_Y, f"{where}: longitude out of range"
    if item.command == Cmd.NAV_LOITER_TIME and not (
        math.isfinite(item.param1) and item.param1 >= 0
    ):
        return MissionResult.INVALID_PARAM1, f"{where}: loiter time must be >= 0 s"
    if math.isnan(item.z) and item.command != Cmd.NAV_LAND:
        return MissionResult.INVALID_PARAM7, f"{where}: altitude missing"
    x_m, y_m, z_m = item.local_target_m(origin, home_m, home_m)
    if item.command != Cmd.NAV_LAND and math.isfinite(z_m):
        if z_m - home_m[2] > ceiling_m:
            return MissionResult.INVALID_PARAM7, (
                f"{where}: altitude {z_m - home_m[2]:.0f} m above ceiling {ceiling_m:.0f} m"
            )
        if z_m < 0.0:
            return MissionResult.INVALID_PARAM7, f"{where}: altitude below ground"
    if math.hypot(x_m - home_m[0], y_m - home_m[1]) > max_distance_m:
        return MissionResult.INVALID_PARAM5_X, (
            f"{where}: {math.hypot(x_m - home_m[0], y_m - home_m[1]):.0f} m from home, "
            f"limit {max_distance_m:.0f} m"
        )
    return MissionResult.ACCEPTED, ""


def validate_item_limits(item: MissionItem, params: ParamStore) -> tuple[int, str]:
    """Check the speeds and rates of one item against the vehicle's flight envelope now:
    a speed change must name a known speed type and a speed the vehicle can fly (or -1/-2,
    back to the configured speed), a yaw rate must not be vanishingly small."""
    where = f"Item {item.seq}"
    if item.command == Cmd.DO_CHANGE_SPEED:
        kind = item.param1 if math.isfinite(item.param1) else float(SpeedKind.GROUND)
        if kind not in tuple(SpeedKind):
            return MissionResult.INVALID_PARAM1, f"{where}: unknown speed type {kind:g}"
        if item.param2 in (-1.0, -2.0):
            return MissionResult.ACCEPTED, ""
        try:
            check_speed(params, SpeedKind(int(kind)), item.param2, where)
        except CommandRefused as refusal:
            return MissionResult.INVALID_PARAM2, str(refusal)
    elif item.command == Cmd.CONDITION_YAW and math.isfinite(item.param2) and item.param2 > 0:
        try:
            check_yaw_rate(params, item.param2, where)
        except CommandRefused as refusal:
            return MissionResult.INVALID_PARAM2, str(refusal)
    return MissionResult.ACCEPTED, ""
