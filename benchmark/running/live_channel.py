"""Live frames of a session while the benchmark runs it, for a watcher such as `bench run
--web`: the session's world once, then every drone's state and what its tools are doing, at a
fixed wall-clock rate, sent as ``("live", payload)`` messages to the driver wherever the session
runs (this process, a worker process, a Ray node). Watching changes nothing in the run: the
publisher only reads, and it is no thread of the agent, so a lockstep clock never waits on it.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass
from typing import Any

from benchmark.authoring.session_file import Session
from benchmark.running.replay_data import session_world
from emulator.live_state import live_state
from emulator.swarm import Swarm

__all__ = ["LiveChannel", "TaskWatch"]

LiveSend = Callable[[dict[str, Any]], None]


@dataclass
class TaskWatch:
    """What a session is doing now: the current task's text and its tools (set by the episode
    as each task starts)."""

    text: str = ""
    tools: Any = None


@dataclass(frozen=True)
class LiveChannel:
    """Sends live frames of one session at `hz` frames per second of wall time."""

    send: LiveSend
    hz: float = 10.0

    @contextlib.asynccontextmanager
    async def publishing(self, session: Session, swarm: Swarm, trial: int
                         ) -> AsyncIterator[TaskWatch]:
        watch = TaskWatch()
        ident = f"{session.id}-trial{trial}"
        self.send({"id": ident, "name": f"{session.name} (trial {trial})",
                   "scene": session_world(session.data)})
        task = asyncio.create_task(self._run(ident, swarm, watch))
        try:
            yield watch
        finally:
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task
            self.send({"id": ident, "done": True})

    async def _run(self, ident: str, swarm: Swarm, watch: TaskWatch) -> None:
        while True:
            activity = getattr(watch.tools, "activity", None)
            frame = {**live_state(swarm.fleet), "act": activity() if activity else {}}
            self.send({"id": ident, "frame": frame, "task": watch.text})
            await asyncio.sleep(1.0 / self.hz)
