"""Who is thinking: the threads of an agent's control, for a lockstep clock.

A lockstep swarm's clock runs only while every client waits on the world. Each thread of an
agent's control is a `Thinker`: while it computes (between two waits on the world) it pins
the clock, so its next command starts at exactly the simulated time its last outcome came,
however long the model takes. A gateway primitive that waits on the world lets go of the
calling thread's pin while it waits and takes it back at the outcome (see `waiting`).

The current thinker is a context variable: tasks an agent starts inherit it. Threads that
must run side by side (one per drone) each need their own thinker: start them with
`run_concurrently`, which pins the clock for every child until it first waits on the world.
With any other clock the pins are not taken and all of this costs nothing.
"""

from __future__ import annotations

import asyncio
import contextlib
import contextvars
from collections.abc import Awaitable, Iterator, Sequence
from typing import Any, Protocol, TypeVar

__all__ = ["Pinning", "Thinker", "current_thinker", "run_as", "run_concurrently", "waiting"]

T = TypeVar("T")


class Pinning(Protocol):
    """What a thinker needs of a swarm's services."""

    @property
    def lockstep(self) -> bool: ...
    def pin(self) -> object: ...
    def unpin(self, token: object) -> None: ...


_current: contextvars.ContextVar[Thinker | None] = contextvars.ContextVar(
    "mavswarm_thinker", default=None)


class Thinker:
    """One thread of an agent's control (see the module docstring)."""

    def __init__(self, services: Pinning, *, thinking: bool = True) -> None:
        self._services = services
        self._token: object | None = None
        self.closed = False
        if thinking:
            self.think()

    @property
    def thinking(self) -> bool:
        return self._token is not None

    def think(self) -> None:
        """Pin the clock where it is now (the thread computes)."""
        if not self.closed and self._token is None and self._services.lockstep:
            self._token = self._services.pin()

    def wait(self) -> None:
        """Let go of the clock (the thread waits on the world)."""
        token, self._token = self._token, None
        if token is not None:
            self._services.unpin(token)

    def close(self) -> None:
        """The thread is over: it never pins the clock again."""
        self.wait()
        self.closed = True


def current_thinker() -> Thinker | None:
    return _current.get()


@contextlib.contextmanager
def waiting() -> Iterator[Thinker | None]:
    """Around a wait on the world: the calling thread's pin is let go on entry and taken again
    on exit, at the simulated time the wait ended (take it before the wait's own hold goes)."""
    thinker = _current.get()
    if thinker is not None:
        thinker.wait()
    try:
        yield thinker
    finally:
        if thinker is not None:
            thinker.think()


def run_as(thinker: Thinker, call: Awaitable[T]) -> asyncio.Task[T]:
    """Run `call` in a new task whose thread of control is `thinker`."""
    context = contextvars.copy_context()
    context.run(_current.set, thinker)

    async def body() -> T:
        return await call

    return asyncio.get_running_loop().create_task(body(), context=context)


async def run_concurrently(services: Pinning, calls: Sequence[Awaitable[Any]]
                           ) -> list[Any]:
    """Await `calls` side by side, each as its own thread of control; results (or the
    exceptions raised) in order. The caller's thread waits meanwhile and thinks again from
    the moment the last call ends."""
    parent = _current.get()
    left = len(calls)

    async def child(thinker: Thinker, call: Awaitable[Any]) -> Any:
        nonlocal left
        try:
            return await call
        finally:
            left -= 1
            if left == 0 and parent is not None:
                parent.think()  # before the child lets go: no instant without a pin
            thinker.close()

    tasks = [run_as(thinker, child(thinker, call))
             for thinker, call in ((Thinker(services), c) for c in calls)]
    if parent is not None and tasks:
        parent.wait()
    try:
        return list(await asyncio.gather(*tasks, return_exceptions=True))
    finally:
        if parent is not None:
            parent.think()
