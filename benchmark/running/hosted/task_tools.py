"""The episode's own tools, served to an agent outside the process.

A request from an external agent is a call on the very `AgentTools` the episode gave the
hosted agent, so it is counted, logged and judged as an in-process agent's call. What is
added changes no outcome:

- a request runs as the episode's thread of control (its `Thinker`): with a lockstep clock,
  simulated time passes while a request waits on the world and stands still between
  requests, exactly as for an in-process agent that awaits the same calls one by one. A key
  is one thread, so under lockstep it runs one call at a time: a call while another runs is
  `rejected` (nothing done, nothing counted), since where it would start in simulated time
  would depend on the wall clock. Calls meant to run side by side go through
  `tools.concurrently` (a batch tool), each then a thread of its own;
- every call runs in the event loop's thread, also when a synchronous route calls a read
  from a worker thread;
- the task's end is noticed where it happens (`finish`, a spent budget), before the answer
  goes back, so the next task is offered as soon as the agent asks for it.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import functools
import inspect
import threading
from collections.abc import Awaitable, Callable
from typing import Any

from agent_contract import AgentTools, BudgetExhausted, tool_names
from mavlink_gateway import Outcome, Status
from mavlink_gateway.pacing import Thinker, current_thinker, run_as

__all__ = ["HostedTools"]

_TOOLS = frozenset(tool_names())


class HostedTools:
    """`tools` served to one outside agent (see the module doc): made in the episode's loop,
    by the agent's `run`; `lockstep`: the one-call-at-a-time rule applies. `on_end()` is
    called in the loop's thread when the task ends through a tool. Everything that is not a
    tool (counters, the call log, `spent`, `finished`) reads through to `tools`."""

    def __init__(self, tools: AgentTools, thinker: Thinker | None,
                 on_end: Callable[[], None], *, lockstep: bool) -> None:
        self._tools = tools
        self._thinker = thinker
        self._on_end = on_end
        self._lockstep = lockstep
        self._running: str | None = None
        self._loop = asyncio.get_running_loop()
        self._loop_thread = threading.get_ident()
        self._wrapped: dict[str, Any] = {}

    @property
    def over(self) -> bool:
        return self._tools.finished or self._tools.spent is not None

    def _ended(self) -> None:
        if self.over:
            self._on_end()

    def __getattr__(self, name: str) -> Any:
        attr = getattr(self._tools, name)
        if name not in _TOOLS:
            return attr
        wrapped = self._wrapped.get(name)
        if wrapped is None:
            wrapped = self._wrap(name, attr)
            self._wrapped[name] = wrapped
        return wrapped

    def _refusal(self, name: str) -> Outcome | None:
        if not self._lockstep or self._running is None:
            return None
        return Outcome(Status.REJECTED, f"{name} refused: this task's agent is still running "
                       f"{self._running} (one call at a time under the lockstep clock: send "
                       "calls that should run side by side in one batch call)")

    async def _top(self, name: str, call: Callable[[], Awaitable[Any]]) -> Any:
        """A call that a request makes (not one inside a batch, which is a thread of its
        own already): as the episode's thread, one at a time."""
        refused = self._refusal(name)
        if refused is not None:
            return refused
        self._running = name
        try:
            if self._thinker is None:
                return await call()
            return await run_as(self._thinker, call())
        finally:
            self._running = None

    async def concurrently(self, *calls: Awaitable[Any]) -> list[Any]:
        """`AgentTools.concurrently` as the episode's thread: it waits while its calls, each
        a thread of its own, run side by side."""
        if current_thinker() is not None:
            return await self._tools.concurrently(*calls)
        result = await self._top("batch", lambda: self._tools.concurrently(*calls))
        if isinstance(result, Outcome):  # refused: the calls never run
            for call in calls:
                if inspect.iscoroutine(call):
                    call.close()
            return [result] * len(calls)
        return list(result)

    def _wrap(self, name: str, method: Callable[..., Any]) -> Callable[..., Any]:
        if inspect.iscoroutinefunction(method):
            @functools.wraps(method)
            async def call_async(*args: Any, **kwargs: Any) -> Any:
                try:
                    if current_thinker() is not None:  # inside a batch: its own thread
                        return await method(*args, **kwargs)
                    return await self._top(name, lambda: method(*args, **kwargs))
                except BudgetExhausted:
                    self._on_end()
                    raise
                finally:
                    self._ended()
            return call_async

        def in_loop(*args: Any, **kwargs: Any) -> Any:
            refused = None if current_thinker() is not None else self._refusal(name)
            if refused is not None:
                return refused
            try:
                return method(*args, **kwargs)
            except BudgetExhausted:
                self._on_end()
                raise
            finally:
                self._ended()

        @functools.wraps(method)
        def call_sync(*args: Any, **kwargs: Any) -> Any:
            if threading.get_ident() == self._loop_thread:
                return in_loop(*args, **kwargs)
            # A synchronous route runs in a worker thread: the call itself runs in the loop's
            # thread, like every other call on the world, one at a time.
            done: concurrent.futures.Future[Any] = concurrent.futures.Future()

            def run() -> None:
                try:
                    done.set_result(in_loop(*args, **kwargs))
                except BaseException as error:
                    done.set_exception(error)

            self._loop.call_soon_threadsafe(run)
            return done.result()
        return call_sync
