"""The episode's own tools, served to an agent outside the process.

A request from an external agent is a call on the very `AgentTools` the episode gave the
hosted agent, so it is counted, logged and judged as an in-process agent's call. Two things
are added, nothing changed:

- every tool runs as the episode's thread of control (its `Thinker`): with a lockstep clock,
  simulated time passes while a request waits on the world and stands still between
  requests, exactly as for an in-process agent that awaits the same calls one by one;
- the task's end is noticed where it happens (`finish`, a spent budget), before the answer
  goes back, so the next task is offered as soon as the agent asks for it.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import functools
import inspect
import threading
from collections.abc import Callable
from typing import Any

from agent_contract import AgentTools, BudgetExhausted, tool_names
from mavlink_gateway.pacing import Thinker, run_as

__all__ = ["HostedTools"]

_TOOLS = frozenset(tool_names())


class HostedTools:
    """`tools` with every tool run as `thinker`, in the loop's thread (made in it); `on_end()`
    is called, in that thread, when the task ends through a tool (finish, or a call that
    finds the budget spent). Everything else (counters, the call log, `spent`, `finished`)
    reads through to `tools`."""

    def __init__(self, tools: AgentTools, thinker: Thinker | None,
                 on_end: Callable[[], None]) -> None:
        self._tools = tools
        self._thinker = thinker
        self._on_end = on_end
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
            wrapped = self._wrap(attr)
            self._wrapped[name] = wrapped
        return wrapped

    def _wrap(self, method: Callable[..., Any]) -> Callable[..., Any]:
        if inspect.iscoroutinefunction(method):
            @functools.wraps(method)
            async def call_async(*args: Any, **kwargs: Any) -> Any:
                try:
                    if self._thinker is None:
                        return await method(*args, **kwargs)
                    return await run_as(self._thinker, method(*args, **kwargs))
                except BudgetExhausted:
                    self._on_end()
                    raise
                finally:
                    self._ended()
            return call_async

        def in_loop(*args: Any, **kwargs: Any) -> Any:
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
