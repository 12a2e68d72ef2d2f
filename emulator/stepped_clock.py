"""A stepped swarm's clock: how far its scheduler may step, and who waits on simulated time.

Callers advance the clock to a target (`advance`), wait for the fleet to come to rest
(`wait_idle`) or hold it at a time until they release it (`hold_at`: an outcome waited on with
a simulated-time budget times out at exactly its budget, and a thinking client pins the clock
where it stands). The swarm's scheduler asks `should_step` and `steps_allowed` between slices
and calls `release_waiters` after each, passing the times other parts need the clock to reach
or stop at (lockstep watches, fault events).
"""

from __future__ import annotations

import asyncio
import math
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from emulator.flight.fleet import Fleet

__all__ = ["MAX_STEPS_PER_RUN", "SteppedClock"]

MAX_STEPS_PER_RUN = 2000  # steps one run may take while vehicles are busy


class SteppedClock:
    """Advance targets, holds and waiters of one fleet's stepped clock."""

    def __init__(self, fleet: Fleet, wake: Callable[[], None]) -> None:
        """wake: have the scheduler look again (a target or hold changed)."""
        self._fleet = fleet
        self._wake = wake
        self._advance_to_s = 0.0
        self._advance_waiters: list[tuple[float, asyncio.Future[None]]] = []
        self._idle_waiters: list[asyncio.Future[None]] = []
        self._holds: dict[object, float] = {}

    # ----------------------------------------------------------------- callers
    async def advance_to(self, target_s: float) -> None:
        """Return once the clock reached target_s (it runs there even if nothing moves)."""
        self._advance_to_s = max(self._advance_to_s, target_s)
        fut: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        self._advance_waiters.append((target_s, fut))
        self._wake()
        await fut

    async def wait_idle(self) -> None:
        """Return once no vehicle is executing a goal."""
        if not self._fleet.any_busy:
            return
        fut: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        self._idle_waiters.append(fut)
        self._wake()
        await fut

    def hold_at(self, t_s: float) -> object:
        """Never step past t_s until `release(token)`; returns the token."""
        token = object()
        self._holds[token] = t_s
        return token

    def release(self, token: object) -> None:
        if self._holds.pop(token, None) is not None:
            self._wake()

    def cancel_waiters(self) -> None:
        """The swarm closes: every caller still waiting is cancelled."""
        for _, fut in self._advance_waiters:
            if not fut.done():
                fut.cancel()
        for fut in self._idle_waiters:
            if not fut.done():
                fut.cancel()

    # --------------------------------------------------------------- scheduler
    def held_at(self) -> float:
        return min(self._holds.values()) if self._holds else math.inf

    def should_step(self, targets: Iterable[float]) -> bool:
        """Whether to step now: not at a hold, and a vehicle is busy or the clock has an
        advance target ahead (its own, or one of `targets`)."""
        now = self._fleet.now_s
        if now + 1e-9 >= self.held_at():
            return False
        if self._fleet.any_busy or now + 1e-9 < self._advance_to_s:
            return True
        return any(now + 1e-9 < t for t in targets)

    def steps_allowed(self, targets: Iterable[float]) -> int:
        """Steps the clock may run now: up to the next advance target (its own, a waiter's
        or one of `targets`) when idle, and never past a hold."""
        fleet = self._fleet
        now, dt = fleet.now_s, fleet.dt_s
        limit = MAX_STEPS_PER_RUN if fleet.any_busy else 0
        ahead = [t for t in (*(t for t, _ in self._advance_waiters), self._advance_to_s,
                             *targets)
                 if t > now + 1e-9 and math.isfinite(t)]
        if ahead:
            to_target = math.ceil((min(ahead) - now) / dt - 1e-9)
            limit = to_target if limit == 0 else min(limit, to_target)
        held = self.held_at()
        if math.isfinite(held):
            limit = min(limit, math.ceil((held - now) / dt - 1e-9))
        return max(1, limit)

    def release_waiters(self) -> None:
        """Wake the callers whose target the clock reached, and those waiting for rest once
        no vehicle is busy."""
        now = self._fleet.now_s
        if self._advance_waiters:
            keep = []
            for target, fut in self._advance_waiters:
                if now + 1e-9 >= target:
                    if not fut.done():
                        fut.set_result(None)
                else:
                    keep.append((target, fut))
            self._advance_waiters = keep
        if self._idle_waiters and not self._fleet.any_busy:
            for fut in self._idle_waiters:
                if not fut.done():
                    fut.set_result(None)
            self._idle_waiters = []
