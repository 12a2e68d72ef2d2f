"""The bus's view of a swarm in this process: each drone as its own telemetry reports it.

It reads exactly what the vehicles' MAVLink telemetry encodes (position, velocity, heading,
battery, mode, armed, landed state, home) straight from the autopilots, without a MAVLink
round trip, and hears what each autopilot says (STATUSTEXT, photos) through a listener placed
beside its MAVLink link. A photo's targets are those in the drone's own sensor footprint.
Nothing else of the world (targets no drone perceives, obstacles, checks) is read.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import numpy as np

from emulator.flight.camera import ImageCapture
from emulator.flight.listener import AutopilotListener
from emulator.flight.mission import MissionItem
from emulator.swarm import Swarm
from mavlink_vocabulary import derive_flight_state
from mqtt_bus.payload_types import EventPayload
from mqtt_bus.payloads import DroneSample, photo_event, statustext_event

__all__ = ["SwarmView"]


class _Tee:
    """Forwards everything to the autopilot's MAVLink link and tells the bus what it says."""

    def __init__(self, link: AutopilotListener, on_text: Callable[[int, str], None],
                 on_photo: Callable[[ImageCapture], None]) -> None:
        self.link = link
        self._on_text = on_text
        self._on_photo = on_photo

    def on_statustext(self, severity: int, text: str) -> None:
        self.link.on_statustext(severity, text)
        self._on_text(severity, text)

    def on_image_captured(self, capture: ImageCapture) -> None:
        self.link.on_image_captured(capture)
        self._on_photo(capture)

    def on_mission_item_reached(self, seq: int) -> None:
        self.link.on_mission_item_reached(seq)

    def on_mission_current(self) -> None:
        self.link.on_mission_current()

    def on_payload_item(self, item: MissionItem) -> None:
        self.link.on_payload_item(item)

    def on_home_changed(self) -> None:
        self.link.on_home_changed()

    def on_state_changed(self) -> None:
        self.link.on_state_changed()

    def on_operator_reset(self) -> None:
        self.link.on_operator_reset()


class SwarmView:
    """Samples and events of an in-process swarm. `primitive_of(drone)`: the gateway
    primitive running for a drone (None: none, or no gateway). Call `close()` to take the
    listeners away again."""

    def __init__(self, swarm: Swarm,
                 primitive_of: Callable[[str], str | None] | None = None) -> None:
        self._swarm = swarm
        self._fleet = swarm.fleet
        self._origin = swarm.fleet.world.origin
        self.primitive_of = primitive_of
        self._events: list[EventPayload] = []
        self._tees: list[tuple[Any, _Tee]] = []
        self._homes: dict[tuple[float, float, float], tuple[float, float, float]] = {}
        for ap in self._fleet.autopilots:
            tee = _Tee(ap.listener, functools.partial(self._text, ap.vehicle_id),
                       functools.partial(self._photo, ap.vehicle_id))
            ap.listener = tee
            self._tees.append((ap, tee))

    @property
    def drone_ids(self) -> list[str]:
        return [ap.vehicle_id for ap in self._fleet.autopilots]

    def clock_s(self) -> float:
        return self._fleet.now_s

    def close(self) -> None:
        for ap, tee in self._tees:
            if ap.listener is tee:
                ap.listener = tee.link
        self._tees.clear()

    def _text(self, drone: str, severity: int, text: str) -> None:
        self._events.append(statustext_event(drone, self._fleet.now_s, int(severity), text))

    def _photo(self, drone: str, capture: ImageCapture) -> None:
        self._events.append(photo_event(drone, capture.t_s, capture.index, capture.position_m,
                                        sorted(capture.targets)))

    def add_event(self, event: EventPayload) -> None:
        """An event heard elsewhere (the radio), published with the others."""
        self._events.append(event)

    def drain_events(self) -> list[EventPayload]:
        events, self._events = self._events, []
        return events

    def samples(self) -> list[DroneSample]:
        """Every drone now, rounded as published (vectorised: a 250-drone swarm at 10 Hz)."""
        fleet = self._fleet
        dyn = fleet.dyn
        origin = self._origin
        lon_per_m, lat_per_m = origin.scale()
        pos = dyn.position_m
        lat = np.round(origin.latitude_deg + pos[:, 1] * lat_per_m, 8).tolist()
        lon = np.round(origin.longitude_deg + pos[:, 0] * lon_per_m, 8).tolist()
        amsl = np.round(origin.altitude_amsl_m + pos[:, 2], 2).tolist()
        positions = np.round(pos, 2).tolist()
        velocities = np.round(dyn.velocity_m_s, 2).tolist()
        speeds = np.linalg.norm(dyn.velocity_m_s, axis=1).tolist()
        yaws = np.round(np.mod(dyn.yaw_deg, 360.0), 1).tolist()
        battery = np.round(fleet.bat.pct, 1).tolist()
        armed = fleet.armed.tolist()
        airborne = fleet.airborne.tolist()
        now = round(fleet.now_s, 3)
        primitive_of = self.primitive_of
        out = []
        for k, ap in enumerate(fleet.autopilots):
            drone = ap.vehicle_id
            home = ap.home_m
            home_geo = self._homes.get(home)
            if home_geo is None:
                hlat, hlon, halt = origin.to_geodetic(*home)
                home_geo = self._homes[home] = (round(hlat, 8), round(hlon, 8), round(halt, 2))
            x, y, z = positions[k]
            ve, vn, vu = velocities[k]
            out.append(DroneSample(
                drone=drone, time_s=now, position_m=(x, y, z),
                geodetic=(lat[k], lon[k], amsl[k]), velocity_m_s=(ve, vn, vu),
                heading_deg=yaws[k], battery_pct=battery[k], mode=ap.mode.name.lower(),
                armed=armed[k],
                flight_state=derive_flight_state(ap.landed_state.value, airborne[k],
                                                 speeds[k]),
                home_m=home, home_geodetic=home_geo,
                primitive=primitive_of(drone) if primitive_of else None,
            ))
        return out

