"""The STATUSTEXT messages an emulated vehicle sends of its own accord, as types, and the one pair
of functions that writes them (`build_statustext`, in the emulator) and reads them back
(`parse_statustext`, in the gateway and the MQTT bus).

Each message type holds what its text says and the severity it is sent with. A text no type
describes (a refusal's reason, "Landing detected" ...) reads back as `FreeText`. MAVLink carries
at most STATUSTEXT_MAX_CHARS characters: an obstacle hold whose text was cut there still reads
as `ObstacleHold`, its name as far as it came.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum
from typing import ClassVar

from mavlink_vocabulary.enums import MavSeverity

__all__ = [
    "GOAL_ENDING_MESSAGES",
    "OUT_OF_TASK_MESSAGES",
    "STATUSTEXT_MAX_CHARS",
    "Announcement",
    "BatteryFailsafe",
    "BatteryFailure",
    "BatteryLevel",
    "DataLinkLost",
    "FailsafeAction",
    "FailuresCleared",
    "FreeText",
    "GeofenceAction",
    "GeofenceBreached",
    "GeofenceReached",
    "GpsLost",
    "LowBattery",
    "ManualControlLost",
    "MotorFailure",
    "ObstacleHold",
    "OffboardLost",
    "StatusMessage",
    "build_statustext",
    "parse_statustext",
]

STATUSTEXT_MAX_CHARS = 50
"""The length of STATUSTEXT's text field: a longer text is cut there on the wire."""


class BatteryLevel(StrEnum):
    """The battery failsafe levels, as the text names them."""

    CRITICAL = "Critical"  # the vehicle returns home
    EMERGENCY = "Emergency"  # the vehicle lands where it is


class FailsafeAction(StrEnum):
    """What a link-loss failsafe does (NAV_DLL_ACT / NAV_RCL_ACT), as the text names it."""

    HOLD = "hold"
    RETURN = "return"
    LAND = "land"


class GeofenceAction(StrEnum):
    """What a geofence breach does (GF_ACTION), as the text's ending names it."""

    WARN = ""
    HOLD = "holding"
    RETURN = "returning"
    TERMINATE = "flight terminated"
    LAND = "landing"


@dataclass(frozen=True, slots=True)
class ObstacleHold:
    """An obstacle ahead stopped the vehicle; it holds."""

    obstacle: str
    severity: ClassVar[MavSeverity] = MavSeverity.WARNING


@dataclass(frozen=True, slots=True)
class LowBattery:
    pct: float  # sent as a whole percent
    severity: ClassVar[MavSeverity] = MavSeverity.WARNING


@dataclass(frozen=True, slots=True)
class BatteryFailsafe:
    """A battery failsafe: critical returns home, emergency lands."""

    level: BatteryLevel
    pct: float  # sent as a whole percent
    severity: ClassVar[MavSeverity] = MavSeverity.CRITICAL

    @property
    def action(self) -> str:
        return "returning home" if self.level is BatteryLevel.CRITICAL else "landing"


@dataclass(frozen=True, slots=True)
class OffboardLost:
    """Offboard set-points stopped arriving; the vehicle holds."""

    severity: ClassVar[MavSeverity] = MavSeverity.WARNING


@dataclass(frozen=True, slots=True)
class GeofenceReached:
    """A velocity set-point reached the geofence; the vehicle holds."""

    severity: ClassVar[MavSeverity] = MavSeverity.WARNING


@dataclass(frozen=True, slots=True)
class GeofenceBreached:
    action: GeofenceAction

    @property
    def severity(self) -> MavSeverity:
        if self.action is GeofenceAction.TERMINATE:
            return MavSeverity.CRITICAL
        return MavSeverity.WARNING


@dataclass(frozen=True, slots=True)
class DataLinkLost:
    """No ground station heard for COM_DL_LOSS_T: the data-link failsafe acts."""

    action: FailsafeAction
    severity: ClassVar[MavSeverity] = MavSeverity.CRITICAL


@dataclass(frozen=True, slots=True)
class ManualControlLost:
    """No manual control input for COM_RC_LOSS_T; None: the sticks are centred."""

    action: FailsafeAction | None
    severity: ClassVar[MavSeverity] = MavSeverity.CRITICAL


@dataclass(frozen=True, slots=True)
class MotorFailure:
    """A motor failed: the vehicle is going down (in the air) or out of service."""

    falling: bool
    severity: ClassVar[MavSeverity] = MavSeverity.EMERGENCY


@dataclass(frozen=True, slots=True)
class GpsLost:
    """No position estimate: the vehicle lands (in the air) or stays out of the task."""

    landing: bool
    severity: ClassVar[MavSeverity] = MavSeverity.CRITICAL


@dataclass(frozen=True, slots=True)
class BatteryFailure:
    pct: float  # sent as a whole percent
    severity: ClassVar[MavSeverity] = MavSeverity.CRITICAL


@dataclass(frozen=True, slots=True)
class FailuresCleared:
    """The operator repaired the vehicle."""

    severity: ClassVar[MavSeverity] = MavSeverity.INFO


@dataclass(frozen=True, slots=True)
class FreeText:
    """Any other text (a refusal's reason, a notice); its sender chose the severity."""

    text: str


Announcement = (ObstacleHold | LowBattery | BatteryFailsafe | OffboardLost | GeofenceReached
                | GeofenceBreached | DataLinkLost | ManualControlLost | MotorFailure | GpsLost
                | BatteryFailure | FailuresCleared)
"""A message a vehicle sends of its own accord, with its severity."""
StatusMessage = Announcement | FreeText

GOAL_ENDING_MESSAGES: tuple[type, ...] = (BatteryFailsafe, OffboardLost, DataLinkLost)
"""Failsafes that end a goal: the vehicle returns, lands or holds on its own."""
OUT_OF_TASK_MESSAGES: tuple[type, ...] = (MotorFailure, GpsLost)
"""Failures that take the vehicle out of the task."""


def build_statustext(message: StatusMessage) -> str:
    """The text the vehicle sends for `message`."""
    match message:
        case ObstacleHold(obstacle):
            return f"Obstacle {obstacle} ahead: holding"
        case LowBattery(pct):
            return f"Low battery: {pct:.0f}% remaining"
        case BatteryFailsafe(level, pct):
            return f"{level.value} battery {pct:.0f}%: {message.action}"
        case OffboardLost():
            return "Offboard setpoints lost: holding"
        case GeofenceReached():
            return "Geofence reached: holding"
        case GeofenceBreached(action):
            return f"Geofence breached: {action.value}" if action.value else "Geofence breached"
        case DataLinkLost(action):
            return f"Data link lost: failsafe {action.value}"
        case ManualControlLost(action):
            return f"Manual control lost: failsafe {action.value if action else 'sticks centred'}"
        case MotorFailure(falling):
            return f"Motor failure: vehicle {'going down' if falling else 'out of service'}"
        case GpsLost(landing):
            return f"GPS lost: no position estimate{', landing' if landing else ''}"
        case BatteryFailure(pct):
            return f"Battery failure: {pct:.0f}% remaining"
        case FailuresCleared():
            return "Failures cleared by the operator"
        case FreeText(text):
            return text
    raise TypeError(f"not a STATUSTEXT message: {message!r}")


def _options(values: type[StrEnum]) -> str:
    return "|".join(re.escape(v.value) for v in values if v.value)


_PCT = r"(-?(?:0|[1-9]\d*))"  # a whole percent as `{pct:.0f}` writes it
_PARSERS: tuple[tuple[re.Pattern[str], Callable[[re.Match[str]], StatusMessage]], ...] = (
    (re.compile(r"Obstacle (.+) ahead: holding", re.DOTALL), lambda m: ObstacleHold(m[1])),
    (re.compile(rf"Low battery: {_PCT}% remaining"), lambda m: LowBattery(float(m[1]))),
    (re.compile(rf"(Critical) battery {_PCT}%: returning home"
                rf"|(Emergency) battery {_PCT}%: landing"),
     lambda m: BatteryFailsafe(BatteryLevel(m[1] or m[3]), float(m[2] or m[4]))),
    (re.compile(r"Offboard setpoints lost: holding"), lambda m: OffboardLost()),
    (re.compile(r"Geofence reached: holding"), lambda m: GeofenceReached()),
    (re.compile(rf"Geofence breached(?:: ({_options(GeofenceAction)}))?"),
     lambda m: GeofenceBreached(GeofenceAction(m[1] or ""))),
    (re.compile(rf"Data link lost: failsafe ({_options(FailsafeAction)})"),
     lambda m: DataLinkLost(FailsafeAction(m[1]))),
    (re.compile(rf"Manual control lost: failsafe ({_options(FailsafeAction)}|sticks centred)"),
     lambda m: ManualControlLost(None if m[1] == "sticks centred" else FailsafeAction(m[1]))),
    (re.compile(r"Motor failure: vehicle (going down|out of service)"),
     lambda m: MotorFailure(m[1] == "going down")),
    (re.compile(r"GPS lost: no position estimate(, landing)?"), lambda m: GpsLost(bool(m[1]))),
    (re.compile(rf"Battery failure: {_PCT}% remaining"), lambda m: BatteryFailure(float(m[1]))),
    (re.compile(r"Failures cleared by the operator"), lambda m: FailuresCleared()),
)
_CUT_OBSTACLE = re.compile(r"Obstacle (.+)", re.DOTALL)


@functools.lru_cache(maxsize=4096)
def parse_statustext(text: str) -> StatusMessage:
    """What a STATUSTEXT's text says: the message `build_statustext` wrote it from, else
    `FreeText`. An obstacle hold cut at STATUSTEXT_MAX_CHARS keeps its kind."""
    for pattern, make in _PARSERS:
        found = pattern.fullmatch(text)
        if found:
            return make(found)
    if len(text) == STATUSTEXT_MAX_CHARS:
        cut = _CUT_OBSTACLE.fullmatch(text)
        if cut:
            return ObstacleHold(cut[1])
    return FreeText(text)
