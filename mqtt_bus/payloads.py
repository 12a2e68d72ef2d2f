"""What the bus publishes, as plain JSON-ready data: a drone's sample (what its own telemetry
reports) becomes an `osd` payload and a `state` payload; events are built here too. Each
builder returns the typed dict of its payload (`mqtt_bus.payload_types`), from which the
published JSON Schemas are generated."""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, cast

from mavlink_vocabulary import (
    BatteryFailsafe,
    BatteryLevel,
    FlightState,
    GeofenceReached,
    ObstacleHold,
    OffboardLost,
    StatusMessage,
    parse_statustext,
)
from mqtt_bus.payload_types import (
    BenchProgressPayload,
    BenchStatusPayload,
    EventPayload,
    FailsafeEvent,
    Home,
    ObstacleHoldEvent,
    OsdPayload,
    PhotoEvent,
    RadioEvent,
    StatePayload,
    StatusPayload,
    StatustextEvent,
)

__all__ = [
    "FAILSAFE_ACTIONS",
    "FAILSAFE_REASONS",
    "DroneSample",
    "bench_progress_payload",
    "bench_status_payload",
    "encode",
    "osd_payload",
    "photo_event",
    "radio_event",
    "state_payload",
    "status_payload",
    "statustext_event",
]



def _failsafe(message: StatusMessage) -> tuple[str, str] | None:
    """(reason, action) of a failsafe event, for the messages the bus reports as one."""
    match message:
        case BatteryFailsafe(level=level):
            return f"battery_{level.lower()}", message.action.replace(" ", "_")
        case OffboardLost():
            return "offboard_lost", "hold"
        case GeofenceReached():
            return "geofence", "hold"
    return None


_BUS_FAILSAFES: list[StatusMessage] = [*(BatteryFailsafe(level, 0.0) for level in BatteryLevel),
                                       OffboardLost(), GeofenceReached()]
_FAILSAFES = [_failsafe(m) for m in _BUS_FAILSAFES]
FAILSAFE_REASONS: tuple[str, ...] = tuple(dict.fromkeys(f[0] for f in _FAILSAFES if f))
"""Every `reason` of a failsafe event."""
FAILSAFE_ACTIONS: tuple[str, ...] = tuple(dict.fromkeys(f[1] for f in _FAILSAFES if f))
"""Every `action` of a failsafe event."""


def _r(value: float, digits: int = 2) -> float | None:
    return round(value, digits) if value - value == 0.0 else None  # None: NaN or infinite


@dataclass(frozen=True, slots=True)
class DroneSample:
    """One drone as its own telemetry reports it at simulated time `time_s` (local ENU metres
    from the session origin's ground, WGS84, compass heading)."""

    drone: str
    time_s: float
    position_m: tuple[float, float, float]
    geodetic: tuple[float, float, float]  # latitude_deg, longitude_deg, altitude_amsl_m
    velocity_m_s: tuple[float, float, float]  # east, north, up
    heading_deg: float
    battery_pct: float
    mode: str
    armed: bool
    flight_state: FlightState  # one of TELEMETRY_FLIGHT_STATES
    home_m: tuple[float, float, float] | None
    home_geodetic: tuple[float, float, float] | None
    primitive: str | None = None  # the gateway primitive running for it, if any


def osd_payload(s: DroneSample) -> OsdPayload:
    x, y, z = s.position_m
    home_z = s.home_m[2] if s.home_m is not None else 0.0
    lat, lon, alt = s.geodetic
    ve, vn, vu = s.velocity_m_s
    return {
        "drone": s.drone, "time_s": round(s.time_s, 3),
        "position": {"x_m": _r(x), "y_m": _r(y), "z_m": _r(z), "altitude_m": _r(z - home_z)},
        "wgs84": {"latitude_deg": _r(lat, 8), "longitude_deg": _r(lon, 8),
                  "altitude_amsl_m": _r(alt)},
        "velocity": {"east_m_s": _r(ve), "north_m_s": _r(vn), "up_m_s": _r(vu)},
        "heading_deg": _r(s.heading_deg, 1), "battery_pct": _r(s.battery_pct, 1),
        "mode": s.mode, "armed": s.armed,
    }


def state_payload(s: DroneSample) -> StatePayload:
    """The change-driven part (compare with `time_s` left out)."""
    home: Home | None = None
    if s.home_m is not None and s.home_geodetic is not None:
        hx, hy, hz = s.home_m
        lat, lon, alt = s.home_geodetic
        home = {"x_m": _r(hx), "y_m": _r(hy), "z_m": _r(hz), "latitude_deg": _r(lat, 8),
                "longitude_deg": _r(lon, 8), "altitude_amsl_m": _r(alt)}
    return {"drone": s.drone, "time_s": round(s.time_s, 3),
            "flight_state": s.flight_state,  # type: ignore[typeddict-item]  # a str here
            "mode": s.mode, "armed": s.armed, "home": home, "primitive": s.primitive}


def statustext_event(drone: str, time_s: float, severity: int | None, text: str
                     ) -> EventPayload:
    """A STATUSTEXT, classified: obstacle holds and failsafes get their own kind (the text
    is kept)."""
    time_s = round(time_s, 3)
    message = parse_statustext(text)
    if isinstance(message, ObstacleHold):
        hold: ObstacleHoldEvent = {"drone": drone, "time_s": time_s, "kind": "obstacle_hold",
                                   "severity": severity, "text": text,
                                   "obstacle": message.obstacle}
        return hold
    failsafe = _failsafe(message)
    if failsafe is not None:
        reason, action = failsafe
        event = {"drone": drone, "time_s": time_s, "kind": "failsafe", "severity": severity,
                 "text": text, "reason": reason, "action": action}
        return cast(FailsafeEvent, event)  # reason and action: FAILSAFE_REASONS / _ACTIONS
    plain: StatustextEvent = {"drone": drone, "time_s": time_s, "kind": "statustext",
                              "severity": severity, "text": text}
    return plain


def photo_event(drone: str, time_s: float, index: int, position_m: tuple[float, float, float],
                targets: list[str] | None) -> PhotoEvent:
    """A photo and what it captured as far as the drone perceived it (None: unknown, e.g. a
    vehicle behind a bridge)."""
    x, y, z = position_m
    return {"drone": drone, "time_s": round(time_s, 3), "kind": "photo", "index": index,
            "position": {"x_m": _r(x), "y_m": _r(y), "z_m": _r(z)}, "targets": targets}


def radio_event(sender: str, time_s: float, text: str, to: str | None) -> RadioEvent:
    """A radio message a drone sent (`to` None: a broadcast)."""
    return {"drone": sender, "time_s": round(time_s, 3), "kind": "radio", "to": to,
            "broadcast": to is None, "text": text}


def status_payload(online: bool, session: str, drones: list[str] | None = None,
                   **extra: Any) -> StatusPayload:
    payload: StatusPayload = {"status": "online" if online else "offline", "session": session}
    if drones is not None:
        payload["drones"] = drones
    payload.update(extra)  # type: ignore[typeddict-item]
    return payload


def bench_status_payload(online: bool, run: str) -> BenchStatusPayload:
    return {"status": "online" if online else "offline", "run": run}


def bench_progress_payload(run: str, counts: Mapping[str, int], *,
                           last: Mapping[str, Any] | None = None,
                           records_in_results: int | None = None) -> BenchProgressPayload:
    """A run's counts after a task (`last`: its record) or at the end (`records_in_results`:
    how many records the results file holds)."""
    progress: BenchProgressPayload = {"run": run, "tasks": counts["tasks"],
                                      "passed": counts["passed"], "failed": counts["failed"]}
    if last is not None:
        progress["last"] = {"key": last.get("key"), "session": last.get("session"),
                            "task": last.get("task"), "passed": last.get("passed")}
    if records_in_results is not None:
        progress["finished"] = True
        progress["records_in_results"] = records_in_results
    return progress


def encode(payload: Mapping[str, Any]) -> bytes:
    return json.dumps(payload, separators=(",", ":"), allow_nan=False).encode()
