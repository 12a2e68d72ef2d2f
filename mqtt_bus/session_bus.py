"""One session on the bus: its status (with the Last Will), telemetry, state, events and,
where commands are offered, its services topics."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Awaitable, Callable
from typing import Any

from agent_contract import AgentTools
from mqtt_bus.commands import CommandService, LinkControl
from mqtt_bus.connection import BusConnection
from mqtt_bus.payloads import encode, status_payload
from mqtt_bus.telemetry import FleetView, TelemetryPublisher
from mqtt_bus.topics import SessionTopics
from mqtt_bus.url import BrokerUrl

__all__ = ["SessionBus"]


class SessionBus:
    """Use `async with SessionBus(url, session, view, ...) as bus:`. Without `tools_for`
    the session takes no commands (its services topics are not even subscribed); `link`
    answers the operator's `get_link`/`set_link` (an emulated swarm's link faults)."""

    def __init__(self, url: BrokerUrl, session: str, view: FleetView, *,
                 osd_hz: float = 2.0,
                 tools_for: Callable[[str], Awaitable[AgentTools]] | None = None,
                 refusal: Callable[[], str | None] | None = None,
                 link: LinkControl | None = None,
                 queue_size: int = 10_000, keepalive_s: int = 10,
                 status_extra: dict[str, Any] | None = None) -> None:
        self.topics = SessionTopics(url.prefix, session)
        self.view = view
        drones = list(view.drone_ids)
        extra = status_extra or {}
        self.commands: CommandService | None = None
        self.connection = BusConnection(
            url, client_id=f"mavswarm-{session}-{os.getpid()}-{id(self) % 100_000}",
            status_topic=self.topics.status,
            online_payload=encode(status_payload(True, session, drones,
                                                 commands=tools_for is not None, **extra)),
            offline_payload=encode(status_payload(False, session)),
            subscriptions=[self.topics.services_filter] if tools_for else [],
            incoming=self._incoming if tools_for else None,
            queue_size=queue_size, keepalive_s=keepalive_s)
        if tools_for is not None:
            self.commands = CommandService(self.topics, self.connection, drones, tools_for,
                                           refusal=refusal, link=link)
        self.telemetry = TelemetryPublisher(view, self.connection, self.topics, osd_hz=osd_hz)
        self._stack = contextlib.AsyncExitStack()

    def _incoming(self, topic: str, payload: bytes) -> None:
        if self.commands is not None:
            self.commands.incoming(topic, payload)

    async def __aenter__(self) -> SessionBus:
        await self._stack.enter_async_context(self.connection)
        await self._stack.enter_async_context(self.telemetry)
        return self

    async def __aexit__(self, *exc: object) -> None:
        if self.commands is not None:
            await self.commands.close()
        await self._stack.aclose()
        self.view.close()

    def report(self) -> str:
        """One line: what was published and dropped."""
        s = self.connection.stats
        return (f"MQTT {self.connection.url.redacted()} session {self.topics.session}: "
                f"{s.published} messages published, {s.dropped} dropped "
                f"({s.dropped_full} queue full, {s.dropped_offline} broker unreachable), "
                f"{max(0, s.connects - 1)} reconnects")
