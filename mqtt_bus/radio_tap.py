"""A swarm's services as the gateway sees them, with every radio message it sends heard by
the bus (an `events` message of kind `radio` on the sender's topic)."""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable
from typing import Any

from mavlink_gateway import Services
from mavlink_gateway.interfaces import SensedWorld, WorldWatch
from mqtt_bus.payload_types import EventPayload
from mqtt_bus.payloads import radio_event

__all__ = ["RadioTap"]


class RadioTap:
    """Delegates every service to `inner`; a message sent or broadcast successfully is
    passed to `on_event` as an event payload."""

    def __init__(self, inner: Services, on_event: Callable[[EventPayload], None]) -> None:
        self.inner = inner
        self._on_event = on_event

    def send_message(self, sender: str, recipient: str, text: str) -> Any:
        message = self.inner.send_message(sender, recipient, text)
        self._on_event(radio_event(sender, self.inner.clock_s(), text, recipient))
        return message

    def broadcast(self, sender: str, text: str) -> int:
        count = self.inner.broadcast(sender, text)
        self._on_event(radio_event(sender, self.inner.clock_s(), text, None))
        return count

    # ------------------------------------------------------------ delegated
    def clock_s(self) -> float:
        return self.inner.clock_s()

    def clock_limit(self, t_s: float) -> contextlib.AbstractContextManager[None]:
        return self.inner.clock_limit(t_s)

    @property
    def lockstep(self) -> bool:
        return self.inner.lockstep

    def pin(self) -> object:
        return self.inner.pin()

    def unpin(self, token: object) -> None:
        self.inner.unpin(token)

    def refresh_telemetry(self, drone_id: str) -> None:
        self.inner.refresh_telemetry(drone_id)

    def repeat_status_texts(self, drone_id: str) -> int:
        return self.inner.repeat_status_texts(drone_id)

    def watch(self, drone_id: str | None = None, *, until_s: float = math.inf,
              advance: bool = False, message_for: str | None = None) -> WorldWatch:
        return self.inner.watch(drone_id, until_s=until_s, advance=advance,
                                message_for=message_for)

    async def advance(self, seconds: float) -> None:
        await self.inner.advance(seconds)

    def sense(self, drone_id: str) -> SensedWorld:
        return self.inner.sense(drone_id)

    def read_messages(self, drone_id: str) -> list[Any]:
        return self.inner.read_messages(drone_id)

    def operator_land_all(self) -> None:
        self.inner.operator_land_all()

    def operator_reset_batteries(self, pct: float = 100.0) -> None:
        self.inner.operator_reset_batteries(pct)

    def operator_reset_to_start(self) -> None:
        self.inner.operator_reset_to_start()
