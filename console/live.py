"""A live swarm as the console shows it: its scene once, then frames of every drone's state
pushed to each open page at `rate_hz` (10 Hz by default) while at least one page watches.

A frame is one JSON text built once per tick and sent to every subscriber: simulated time and,
per drone in scene order, position, heading, speed, battery, armed, flight mode, and what the
drone's tools are doing (the primitive it executes, how its last one ended).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from benchmark.server.link_routes import LinkTarget
from console.commands import Commander
from console.frame_rate import DEFAULT_RATE_HZ, check_rate_hz
from emulator.live_state import live_state
from emulator.swarm import Swarm

__all__ = ["DEFAULT_RATE_HZ", "LiveFeed", "LiveSwarm", "check_rate_hz"]

log = logging.getLogger("mavswarm.console")
QUEUE_FRAMES = 2  # a slow page skips frames rather than lagging behind

Activity = Callable[[], dict[str, dict[str, Any]]]


@dataclass
class LiveSwarm:
    """One swarm the console can show: an id, its scene (session-file layout), the swarm in
    this process (or `frames`, the latest state of one running elsewhere), who reports what
    each drone's tools are doing, and the commander for hands-on commands."""

    id: str
    name: str
    scene: dict[str, Any]
    swarm: Swarm | None = None
    activities: list[Activity] = field(default_factory=list)
    commander: Commander | None = None
    task_text: str = ""
    frames: Callable[[], dict[str, Any] | None] | None = None
    links: Callable[[str], LinkTarget] | None = None
    """The swarm's link faults as a caller of that role may use them (None: not here)."""

    def state(self) -> dict[str, Any]:
        """The frame: the fleet's live state and each drone's activity."""
        if self.swarm is not None:
            return {**live_state(self.swarm.fleet), "act": self.activity()}
        latest = self.frames() if self.frames is not None else None
        return latest or {"t": 0.0, "x": [], "y": [], "z": [], "yaw": [], "spd": [], "bat": [],
                          "armed": [], "mode": [], "act": {}}

    def activity(self) -> dict[str, dict[str, Any]]:
        merged: dict[str, dict[str, Any]] = {}
        sources = list(self.activities)
        if self.commander is not None:
            sources.append(self.commander.activity)
        for source in sources:
            for drone, entry in source().items():
                mine = merged.setdefault(drone, {"executing": None, "last": None})
                mine["executing"] = entry.get("executing") or mine["executing"]
                mine["last"] = entry.get("last") or mine["last"]
        return merged


def build_frame(live: LiveSwarm) -> str:
    """The frame of `live` now, as JSON text."""
    return json.dumps(live.state(), separators=(",", ":"))


class LiveFeed:
    """Pushes frames of one live swarm to its subscribers (asyncio queues of JSON text)."""

    def __init__(self, live: LiveSwarm, rate_hz: float = DEFAULT_RATE_HZ) -> None:
        check_rate_hz(rate_hz)
        self.live = live
        self.period_s = 1.0 / rate_hz
        self._subscribers: set[asyncio.Queue[str]] = set()
        self._task: asyncio.Task[None] | None = None
        self.frames_built = 0

    def subscribe(self) -> asyncio.Queue[str]:
        queue: asyncio.Queue[str] = asyncio.Queue(QUEUE_FRAMES)
        self._subscribers.add(queue)
        if self._task is None or self._task.done():
            self._task = asyncio.create_task(self._run(), name=f"console-feed-{self.live.id}")
        return queue

    def unsubscribe(self, queue: asyncio.Queue[str]) -> None:
        self._subscribers.discard(queue)

    async def _run(self) -> None:
        loop = asyncio.get_running_loop()
        next_at = loop.time()
        while self._subscribers:
            try:
                text = build_frame(self.live)
            except Exception:  # a view must never take the swarm down: log, try next tick
                log.exception("live frame of %s failed", self.live.id)
                text = ""
            self.frames_built += 1
            for queue in list(self._subscribers) if text else ():
                if queue.full():
                    with contextlib.suppress(asyncio.QueueEmpty):
                        queue.get_nowait()
                queue.put_nowait(text)
            next_at += self.period_s
            await asyncio.sleep(max(0.0, next_at - loop.time()))
            if loop.time() - next_at > 1.0:  # fell far behind: start again from now
                next_at = loop.time()

    async def aclose(self) -> None:
        self._subscribers.clear()
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
