"""Drone-to-drone messaging: an inbox per drone, every message recorded as ground truth."""

from __future__ import annotations

import math
import re
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from emulator.truth_events import TruthEventKind

if TYPE_CHECKING:
    from emulator.truth import TruthRecorder

__all__ = ["MAX_INBOX", "MAX_TEXT_CHARS", "Message", "Radio", "RadioError"]

MAX_TEXT_CHARS = 500
MAX_INBOX = 200  # oldest messages are dropped beyond this, and the drop is recorded
_UNSENDABLE = re.compile(r"[\ud800-\udfff\x00-\x08\x0b-\x1f\x7f]")


class RadioError(ValueError):
    """Raised when a message cannot be sent (unknown drone; empty, oversized or unencodable
    text)."""


@dataclass(frozen=True, slots=True)
class Message:
    sender: str
    recipient: str
    text: str
    t_s: float
    broadcast: bool = False


class Radio:
    """Delivers text messages between the drones of one swarm."""

    def __init__(self, drone_ids: Sequence[str], recorder: TruthRecorder,
                 clock: Callable[[], float]) -> None:
        self._inboxes: dict[str, deque[Message]] = {d: deque() for d in drone_ids}
        self._recorder = recorder
        self._clock = clock

    def add_drone(self, drone_id: str) -> None:
        """A drone that joined the swarm, with an empty inbox."""
        self._inboxes.setdefault(drone_id, deque())

    def remove_drone(self, drone_id: str) -> None:
        """A drone that left: it neither sends nor receives from now on."""
        self._inboxes.pop(drone_id, None)

    def _check(self, drone_id: str, role: str) -> None:
        if not isinstance(drone_id, str) or drone_id not in self._inboxes:
            known = ", ".join(self._inboxes)
            try:  # the id may be anything a caller passed, even an unhashable or huge value
                shown = repr(drone_id)[:60]
            except ValueError:
                shown = f"<{type(drone_id).__name__}>"
            raise RadioError(f"unknown {role} drone {shown} (known: {known})")

    def _check_text(self, text: str) -> None:
        if not isinstance(text, str) or not text.strip():
            raise RadioError("message text is empty")
        if len(text) > MAX_TEXT_CHARS:
            raise RadioError(f"message text is {len(text)} characters, limit {MAX_TEXT_CHARS}")
        bad = _UNSENDABLE.search(text)
        if bad is not None:
            raise RadioError(f"message text holds an unsendable character "
                             f"(U+{ord(bad.group()):04X}) at character {bad.start()}; send "
                             "valid Unicode text without control characters")

    def _deliver(self, message: Message) -> None:
        inbox = self._inboxes[message.recipient]
        if len(inbox) >= MAX_INBOX:
            dropped = inbox.popleft()
            self._recorder.record_event(message.t_s, message.recipient,
                                        TruthEventKind.MESSAGE_DROPPED, sender=dropped.sender)
        inbox.append(message)

    def send(self, sender: str, recipient: str, text: str) -> Message:
        self._check(sender, "sending")
        self._check(recipient, "receiving")
        if sender == recipient:
            raise RadioError(f"drone {sender} cannot message itself")
        self._check_text(text)
        message = Message(sender, recipient, text, self._clock())
        self._recorder.record_event(message.t_s, sender, TruthEventKind.MESSAGE_SENT,
                                    to=recipient, text=text)
        self._deliver(message)
        return message

    def broadcast(self, sender: str, text: str) -> int:
        self._check(sender, "sending")
        self._check_text(text)
        t_s = self._clock()
        recipients = [d for d in self._inboxes if d != sender]
        self._recorder.record_event(t_s, sender, TruthEventKind.MESSAGE_BROADCAST, text=text,
                                    recipients=recipients)
        for recipient in recipients:
            self._deliver(Message(sender, recipient, text, t_s, broadcast=True))
        return len(recipients)

    def read(self, drone_id: str, *, sent_before_s: float = math.inf) -> list[Message]:
        """The drone's inbox, oldest first, emptied of what was read. `sent_before_s`: only
        messages sent before that time (a lockstep clock delivers a message one physics step
        after it is sent, so clients thinking at the same instant never race each other)."""
        self._check(drone_id, "reading")
        inbox = self._inboxes[drone_id]
        messages = [m for m in inbox if m.t_s < sent_before_s]
        if len(messages) == len(inbox):
            inbox.clear()
        else:
            kept = [m for m in inbox if m.t_s >= sent_before_s]
            inbox.clear()
            inbox.extend(kept)
        if messages:
            self._recorder.record_event(self._clock(), drone_id, TruthEventKind.MESSAGES_READ,
                                        count=len(messages))
        return messages

    def clear(self) -> None:
        for inbox in self._inboxes.values():
            inbox.clear()
