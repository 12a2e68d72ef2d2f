"""Waits on the world for a lockstep clock: simulated time stops where a client must react.

In lockstep pacing, simulated time advances only while every client of the swarm is waiting on
the world. A client says it is waiting by opening a `Watch`: on one vehicle (the clock stops
after the physics step in which that vehicle's goal ends or a failsafe takes it over), up to a
time (the clock stops there), or until a radio message for a drone can be read. Once a watch
halts, it pins the clock at the halt's simulated time until the client resumes or closes it, so
what the client does next starts at that exact time however long it takes in wall time.

Clients that think without a watch pin the clock themselves (`Swarm.pin`).
"""

from __future__ import annotations

import asyncio
import math
from collections.abc import Callable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from emulator.flight.fleet import Fleet

__all__ = ["Watch", "WatchBoard"]


class Watch:
    """One client waiting on the world (see the module docstring)."""

    def __init__(self, board: WatchBoard, k: int | None, until_s: float, advance: bool,
                 message_for: str | None) -> None:
        self._board = board
        self.k = k
        self.until_s = until_s
        self.advance = advance
        self.message_for = message_for
        self.halted_at_s: float | None = None
        self.closed = False
        self._future: asyncio.Future[float] = asyncio.get_running_loop().create_future()
        self._until_hold: object | None = None
        self._pin: object | None = None

    @property
    def at_deadline(self) -> bool:
        """The halt came from the deadline (`until_s`), not from an event."""
        return self.halted_at_s is not None and self.halted_at_s >= self.until_s - 1e-9

    async def halted(self) -> float:
        """Wait for the halt; the simulated time at which the clock stopped."""
        return await asyncio.shield(self._future)

    def halted_now(self) -> bool:
        return self._future.done()

    def resume(self) -> None:
        """Let the clock run on and wait for the next halt (the last one needed nothing)."""
        if self.closed or not self._future.done():
            return
        self.halted_at_s = None
        self._future = asyncio.get_running_loop().create_future()
        self._board.release_pin(self)

    def close(self) -> None:
        """Stop waiting: the clock is no longer pinned or limited by this watch."""
        if self.closed:
            return
        self.closed = True
        self._board.remove(self)

    def _halt(self, now_s: float, pin: object) -> None:
        self.halted_at_s = now_s
        self._pin = pin
        if not self._future.done():
            self._future.set_result(now_s)


class WatchBoard:
    """The open watches of one swarm, checked after every slice of physics steps."""

    def __init__(self, fleet: Fleet, hold: Callable[[float], object],
                 release: Callable[[object], None], burst: Callable[[int], None]) -> None:
        self._fleet = fleet
        self._hold = hold
        self._release = release
        self._burst = burst
        self._watches: list[Watch] = []
        self._stop_counts = [0] * fleet.n

    def add_vehicle(self) -> None:
        """One more vehicle joined the fleet."""
        self._stop_counts.append(0)

    def open(self, k: int | None, until_s: float = math.inf, *, advance: bool = False,
             message_for: str | None = None) -> Watch:
        fleet = self._fleet
        watch = Watch(self, k, until_s, advance, message_for)
        if math.isfinite(until_s):
            watch._until_hold = self._hold(until_s)
        if k is not None:
            self._stop_counts[k] += 1
            fleet.stop_on[k] = True
            fleet.ended[k] = False
        self._watches.append(watch)
        if (k is not None and not fleet.busy[k]) or fleet.now_s >= until_s - 1e-9:
            self._halt(watch)  # nothing to wait for: the client goes on at once
        return watch

    def advance_targets(self) -> list[float]:
        """Times the clock must run to even with every vehicle idle (`wait` tools)."""
        return [w.until_s for w in self._watches if w.advance and w.halted_at_s is None]

    def message_ready(self, recipient: str, at_s: float) -> None:
        """A radio message for `recipient` can be read from `at_s` on: watches waiting for
        one halt there."""
        for watch in self._watches:
            if watch.message_for == recipient and watch.halted_at_s is None \
                    and at_s < watch.until_s:
                watch.until_s = at_s
                if watch._until_hold is not None:
                    self._release(watch._until_hold)
                watch._until_hold = self._hold(at_s)

    def check(self) -> None:
        """Halt every watch whose vehicle ended its goal or whose deadline is reached."""
        fleet = self._fleet
        now = fleet.now_s
        for watch in self._watches:
            if watch.halted_at_s is not None:
                continue
            if (watch.k is not None and fleet.ended[watch.k]) or now >= watch.until_s - 1e-9:
                self._halt(watch)
        fleet.ended[:] = False

    def _halt(self, watch: Watch) -> None:
        watch._halt(self._fleet.now_s, self._hold(self._fleet.now_s))
        if watch.k is not None:
            self._burst(watch.k)

    def release_pin(self, watch: Watch) -> None:
        if watch._pin is not None:
            self._release(watch._pin)
            watch._pin = None

    def remove(self, watch: Watch) -> None:
        self.release_pin(watch)
        if watch._until_hold is not None:
            self._release(watch._until_hold)
            watch._until_hold = None
        if watch.k is not None:
            self._stop_counts[watch.k] -= 1
            if self._stop_counts[watch.k] == 0:
                self._fleet.stop_on[watch.k] = False
        if watch in self._watches:
            self._watches.remove(watch)
        if not watch._future.done():
            watch._future.cancel()
