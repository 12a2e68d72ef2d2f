"""Periodic telemetry, change-driven state and events of one session, from a fleet view."""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections.abc import Sequence
from typing import Any, Protocol

from mqtt_bus.connection import BusConnection
from mqtt_bus.payload_types import EventPayload
from mqtt_bus.payloads import DroneSample, encode, osd_payload, state_payload
from mqtt_bus.topics import SessionTopics

__all__ = ["FleetView", "TelemetryPublisher"]

MAX_OSD_HZ = 50.0


class FleetView(Protocol):
    """What the bus reads of a fleet: samples as the drones report them, and events."""

    @property
    def drone_ids(self) -> Sequence[str]: ...
    def clock_s(self) -> float: ...
    def samples(self) -> list[DroneSample]: ...
    def drain_events(self) -> list[EventPayload]: ...
    def add_event(self, event: EventPayload) -> None: ...
    def close(self) -> None: ...


class TelemetryPublisher:
    """Every `1 / osd_hz` wall seconds: one osd per drone (QoS 0), its state when it changed
    (retained, QoS 1) and the events heard since (QoS 1). Runs as a named task beside the
    physics loop; it only samples and queues, never waits on the broker."""

    def __init__(self, view: FleetView, connection: BusConnection, topics: SessionTopics,
                 *, osd_hz: float = 2.0) -> None:
        if not 0.0 < osd_hz <= MAX_OSD_HZ:
            raise ValueError(f"osd rate {osd_hz!r} Hz outside (0, {MAX_OSD_HZ:g}]")
        self.view = view
        self.connection = connection
        self.topics = topics
        self.period_s = 1.0 / osd_hz
        self._states: dict[str, dict[str, Any]] = {}
        self._task: asyncio.Task[None] | None = None
        self.ticks = 0
        self.busy_s = 0.0  # wall time spent sampling and queueing

    async def __aenter__(self) -> TelemetryPublisher:
        self.publish_once()
        self._task = asyncio.create_task(self._run(), name=f"mqtt-osd-{self.topics.session}")
        return self

    async def __aexit__(self, *exc: object) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
            self._task = None
        self.publish_once()  # the last state and events before the session goes offline

    async def _run(self) -> None:
        next_s = time.monotonic()
        while True:
            next_s += self.period_s
            now = time.monotonic()
            if next_s < now:  # fell behind (a stalled loop): skip, do not burst
                next_s = now + self.period_s
            await asyncio.sleep(next_s - now)
            self.publish_once()

    def publish_once(self) -> None:
        started = time.perf_counter()
        conn, topics = self.connection, self.topics
        for sample in self.view.samples():
            conn.publish(topics.osd(sample.drone), encode(osd_payload(sample)))
            state = state_payload(sample)
            key = {k: v for k, v in state.items() if k != "time_s"}
            if self._states.get(sample.drone) != key:
                self._states[sample.drone] = key
                conn.publish(topics.state(sample.drone), encode(state), qos=1, retain=True)
        for event in self.view.drain_events():
            conn.publish(topics.events(event["drone"]), encode(event), qos=1)
        self.ticks += 1
        self.busy_s += time.perf_counter() - started
