"""The driver's board of hosted tasks: the ones on offer, the ones out with an agent, and
whether the run is over. Units post their notices from whatever thread the backend hands
them over in; every change is applied in the endpoint's event loop, where `/next` waits on it.

`/next` semantics (docs/agents/hosted.md): a task on offer is handed out at once, to one
caller only. With none on offer, the call waits for one while fewer tasks are out than
sessions can be hosted at once (`--workers`, or fewer once fewer units are left); when that
many are out already, it answers 409 (after a short grace, so an agent asking right after its
`finish` gets its next task rather than a 409 while the end of its last one is on its way
from the unit). Once every unit is done, it answers 204.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import time
from collections.abc import Mapping
from typing import Any

from benchmark.running.hosted.offer import Notice, NoticeKind, TaskOffer

__all__ = ["AllOut", "Board", "NotYet"]

GRACE_S = 1.0


class AllOut(Exception):
    """Every session hosted at once has its task out with an agent."""

    def __init__(self, out: list[TaskOffer], workers: int) -> None:
        names = ", ".join(f"{o.session}/{o.task_id}" for o in out)
        super().__init__(f"every task this run hosts at once is already out ({names}): "
                         f"finish one first (the run hosts {workers} session(s) at once now; "
                         "--workers)")


class NotYet(Exception):
    """No task came within the wait; ask again."""


class Board:
    def __init__(self, workers: int, units: int) -> None:
        self.workers = workers
        self.units = units  # (session, trial) units in the run; each closes when done
        self._closed = 0
        self._offers: collections.OrderedDict[str, TaskOffer] = collections.OrderedDict()
        self._out: dict[str, TaskOffer] = {}
        self._over = False
        self._loop: asyncio.AbstractEventLoop | None = None
        self._changed: asyncio.Event | None = None
        self.handed_out = 0

    def bind(self, loop: asyncio.AbstractEventLoop) -> None:
        """Apply changes in `loop` (the endpoint's) from now on."""
        self._loop = loop
        self._changed = asyncio.Event()

    def _apply(self, change: Any, *args: Any) -> None:
        loop = self._loop
        if loop is None:
            raise RuntimeError("the board is not bound to the endpoint's loop yet")
        loop.call_soon_threadsafe(self._run, change, *args)

    def _run(self, change: Any, *args: Any) -> None:
        change(*args)
        changed, self._changed = self._changed, asyncio.Event()
        if changed is not None:
            changed.set()

    # ------------------------------------------------------------- any thread
    def post(self, payload: Mapping[str, Any]) -> None:
        """A unit's notice (the payload of its ``("hosted", ...)`` message)."""
        self._apply(self._post, Notice.model_validate(payload))

    def close(self) -> None:
        """Every unit is done: `/next` answers 204 from now on."""
        self._apply(self._close)

    # --------------------------------------------------------- the loop's thread
    def _post(self, notice: Notice) -> None:
        if notice.kind is NoticeKind.OFFER and notice.offer is not None:
            self._offers[notice.key] = notice.offer
        elif notice.kind is NoticeKind.ENDED:
            self._offers.pop(notice.key, None)
            self._out.pop(notice.key, None)
        elif notice.kind is NoticeKind.CLOSED:
            self._closed += 1

    def _close(self) -> None:
        self._over = True
        self._offers.clear()
        self._out.clear()

    def ended(self, key: str) -> None:
        """The agent ended the task with `key` (the endpoint saw it answer)."""
        self._run(self._post, Notice(kind=NoticeKind.ENDED, key=key))

    def is_out(self, key: str) -> bool:
        return key in self._out

    @property
    def at_once(self) -> int:
        """How many tasks can be out at once now: one per session hosted at once."""
        return max(1, min(self.workers, self.units - self._closed))

    @property
    def over(self) -> bool:
        return self._over

    def counts(self) -> dict[str, Any]:
        return {"on_offer": len(self._offers), "out": len(self._out),
                "handed_out": self.handed_out, "over": self._over,
                "sessions_at_once": self.at_once, "units": self.units,
                "units_done": self._closed}

    async def take(self, wait_s: float) -> TaskOffer | None:
        """The next task for a caller (out with it from now), or None once the run is over.
        Raises AllOut or NotYet (see the module doc)."""
        deadline = time.monotonic() + wait_s
        grace_until: float | None = None
        while True:
            changed = self._changed
            assert changed is not None
            if self._offers:
                key, offer = self._offers.popitem(last=False)
                self._out[key] = offer
                self.handed_out += 1
                return offer
            if self._over:
                return None
            now = time.monotonic()
            if len(self._out) >= self.at_once:
                grace_until = grace_until or now + GRACE_S
                if now >= grace_until:
                    raise AllOut(list(self._out.values()), self.at_once)
            else:
                grace_until = None
            if now >= deadline:
                raise NotYet(f"no task was ready within {wait_s:g} s; ask again")
            until = deadline if grace_until is None else min(deadline, grace_until)
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(changed.wait(), max(0.0, until - now))
