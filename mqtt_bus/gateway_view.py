"""The bus's view of any MAVLink fleet through the gateway: each drone's `DroneLink` telemetry
cache (MAVSDK), its STATUSTEXT and camera captures. Used by `mavswarm mqtt-bridge`, for a
real PX4 SITL, real vehicles or a swarm in another process."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping

from mavlink_gateway import DroneLink
from mqtt_bus.payload_types import EventPayload
from mqtt_bus.payloads import DroneSample, photo_event, statustext_event

__all__ = ["GatewayView"]

_MODES = {"RETURN_TO_LAUNCH": "rtl", "FOLLOW_ME": "follow_me"}


class GatewayView:
    """Samples and events of the drones a gateway holds. `clock_s`: the time stamped on
    samples (default: seconds since the view began)."""

    def __init__(self, drones: Mapping[str, DroneLink], *,
                 clock_s: Callable[[], float] | None = None,
                 primitive_of: Callable[[str], str | None] | None = None) -> None:
        self._drones = drones
        start = time.monotonic()
        self._clock = clock_s or (lambda: time.monotonic() - start)
        self._primitive_of = primitive_of
        self._texts_seen = {d: len(link.status_texts) for d, link in drones.items()}
        self._captures_seen = {d: len(link.captures) for d, link in drones.items()}
        self._events: list[EventPayload] = []

    @property
    def drone_ids(self) -> list[str]:
        return list(self._drones)

    def clock_s(self) -> float:
        return self._clock()

    def add_event(self, event: EventPayload) -> None:
        self._events.append(event)

    def close(self) -> None:
        pass

    def drain_events(self) -> list[EventPayload]:
        now = self._clock()
        events, self._events = self._events, []
        for drone, link in self._drones.items():
            texts = link.status_texts
            for text in texts[self._texts_seen.get(drone, 0):]:
                events.append(statustext_event(drone, now, None, text))
            self._texts_seen[drone] = len(texts)
            captures = link.captures
            for info in captures[self._captures_seen.get(drone, 0):]:
                x, y, z = link.origin.to_local(info.latitude_deg, info.longitude_deg,
                                               info.absolute_altitude_m)
                events.append(photo_event(drone, now, int(info.index), (x, y, z), None))
            self._captures_seen[drone] = len(captures)
        return events

    def samples(self) -> list[DroneSample]:
        now = self._clock()
        out = []
        for drone, link in self._drones.items():
            if link.position_m is None:
                continue
            x, y, z = link.position_m
            home = link.home_m
            out.append(DroneSample(
                drone=drone, time_s=now, position_m=(x, y, z),
                geodetic=link.geodetic(x, y, z), velocity_m_s=link.velocity_m_s,
                heading_deg=link.heading_deg,
                battery_pct=link.battery_pct if math.isfinite(link.battery_pct) else math.nan,
                mode=_MODES.get(link.mode, link.mode.lower()), armed=link.armed,
                flight_state=link.flight_state, home_m=home,
                home_geodetic=link.geodetic(*home) if home is not None else None,
                primitive=self._primitive_of(drone) if self._primitive_of else None,
            ))
        return out
