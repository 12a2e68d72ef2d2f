"""The goal a drone's running primitive pursues, and how another primitive interrupts it.

A hold, or a primitive that replaces the current goal (`replace=True`), asks the running
primitive to end: it looks at its `Goal` before each command it sends and while it waits for
an outcome, and ends with Status.INTERRUPTED. A command already in flight is answered first
(never abandoned half-sent: a late retransmission would undo the hold). A primitive stopped
while it waits sends HOLD itself at once (the drone stops where it is, not a round trip
later), then judges its goal once more on fresh telemetry: a goal reached before the hold is
reported as reached.
"""

from __future__ import annotations

import asyncio

__all__ = ["Goal", "Interrupted"]


class Interrupted(Exception):
    """The primitive's goal was interrupted (by a hold, or a goal that replaced it)."""

    def __init__(self, by: str) -> None:
        super().__init__(by)
        self.by = by


class Goal:
    """The primitive running for one drone: its name, and how another one stops it."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.stop = asyncio.Event()  # set: end as soon as no command is in flight
        self.stopped_by = ""
        self.held = False  # the primitive itself sent HOLD as it ended
        self.ended = asyncio.Event()

    def interrupt(self, by: str) -> None:
        if not self.stop.is_set():
            self.stopped_by = by
            self.stop.set()

    def check(self) -> None:
        """Raise Interrupted if another primitive asked this one to end."""
        if self.stop.is_set():
            raise Interrupted(self.stopped_by)
