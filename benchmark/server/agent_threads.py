"""The threads of a served agent's control, for the lockstep clock (docs/agents/tools.md,
"Serving live sessions").

Under `--clock lockstep` (the default of `serve` and `mcp`) a served task's clock runs only while
every thread of its agent waits on the world, as in `bench run`: each thread is a `Thinker`
that pins the clock from the task's start. A request that runs a tool runs as its thread; the
gateway lets go of the thread's pin while a primitive (a flight, `hover`, `wait`) waits on the
world and takes it back at the outcome, so between two requests the clock stands still however
long the agent thinks.

Which thread a request is: the session's agent (its agent keys, and requests without a key
under `--open`), or, for a session served with per-drone keys, one drone's agent, which sees
that drone's tools only (`swarm_agents.teams.per_drone.DroneView`) and whose `finish` ends its part
(the task ends with the last part). A thread runs one request at a time: a second one while
the first runs is refused (`rejected`, nothing done, nothing counted), since where it would
start in simulated time would depend on the wall clock. Calls that must run side by side go in
one `batch` request (its calls are threads of their own, as `tools.concurrently` makes them),
or come from threads of their own.

A world without tasks (free flight) has nothing to score and is shared with the console and
MQTT, so its agent pins nothing; neither does any agent under `--clock stepped`.
"""

from __future__ import annotations

import contextvars
import functools
import inspect
from collections.abc import Awaitable, Callable, Sequence
from typing import Any, TypeVar, cast

from agent_contract import AgentTask, AgentTools, tool_names
from benchmark.running.tool_log import LoggedTools
from mavlink_gateway import Gateway, Outcome, Status
from mavlink_gateway.pacing import Thinker, run_as
from swarm_agents.teams.per_drone import DroneView

__all__ = ["AgentThread", "ServedTools", "call_tool", "read_tool", "surface_of"]

T = TypeVar("T")

_acting: contextvars.ContextVar[AgentThread | None] = contextvars.ContextVar(
    "mavswarm_served_thread", default=None)


class AgentThread:
    """One thread of a served agent (see the module docstring). `pins`: it holds the clock
    while it thinks (a lockstep task); else it only runs its calls."""

    def __init__(self, tools: ServedTools, name: str, *, pins: bool,
                 view: DroneView | None = None) -> None:
        self.name = name
        self.view = view
        self._tools = tools
        self._thinker = Thinker(tools.services) if pins else None
        self.running: str | None = None  # the tool this thread runs now

    @property
    def surface(self) -> AgentTools:
        """What this thread's calls act on: its drone's view, or the whole task's tools."""
        return cast(AgentTools, self.view) if self.view is not None else self._tools

    def refusal(self, name: str) -> Outcome | None:
        """Why `name` may not start on this thread now (another of its calls runs)."""
        if self._thinker is None or self.running is None:
            return None
        who = f"drone {self.name}'s agent" if self.view is not None else "this agent"
        return Outcome(Status.REJECTED, f"{name} refused: {who} is still running {self.running}"
                       " (one call at a time under the lockstep clock: send calls that should "
                       "run side by side in one batch call, or use one key per drone)")

    async def run(self, name: str, call: Callable[[], Awaitable[T]]) -> T | Outcome:
        """Run `call` (the tool `name`) as this thread; its refusal when the thread is busy."""
        refused = self.refusal(name)
        if refused is not None:
            return refused
        self.running = name
        try:
            if self._thinker is None:
                token = _acting.set(self)
                try:
                    return await call()
                finally:
                    _acting.reset(token)

            async def body() -> T:
                _acting.set(self)  # in the task's own context: its calls run as this thread
                return await call()
            return await run_as(self._thinker, body())
        finally:
            self.running = None
            self._after_call()

    def sync(self, name: str, call: Callable[[], T]) -> T | Outcome:
        """A call that needs no simulated time (a read): runs at once unless refused."""
        refused = self.refusal(name)
        if refused is not None:
            return refused
        token = _acting.set(self)
        try:
            return call()
        finally:
            _acting.reset(token)
            self._after_call()

    def _after_call(self) -> None:
        if self.view is not None and self.view.finished:
            self.close()  # this drone's part is over: the others go on without it
            self._tools.part_finished()

    def close(self) -> None:
        """The thread is over: it never holds the clock again."""
        if self._thinker is not None:
            self._thinker.close()


class ServedTools(LoggedTools):
    """A served task's agent tools, with the threads of its agent (see the module docstring).
    `pins`: the threads hold the clock while they think."""

    def __init__(self, gateway: Gateway, task: AgentTask, *, pins: bool,
                 drones: Sequence[str] = ()) -> None:
        super().__init__(gateway, task)
        self.pins = pins
        self.services = gateway.services
        self.threads: dict[str | None, AgentThread] = {}
        self.split(drones)

    def split(self, drones: Sequence[str]) -> None:
        """One thread per drone in `drones` (per-drone agents), or one for the whole agent
        when empty. Before the task's first call only."""
        for thread in self.threads.values():
            thread.close()
        unknown = [d for d in drones if d not in self._gw.drones]
        if unknown:
            raise ValueError(f"drones {unknown} are not in the session "
                             f"({', '.join(self._gw.drones)})")
        if drones:
            self.threads = {d: AgentThread(self, d, pins=self.pins, view=DroneView(self, d))
                            for d in drones}
        else:
            self.threads = {None: AgentThread(self, "agent", pins=self.pins)}

    @property
    def drone_threads(self) -> list[str]:
        """The drones with an agent of their own (empty: one agent for all)."""
        return [d for d in self.threads if d is not None]

    def thread(self, drone: str | None = None) -> AgentThread | None:
        """The thread of `drone`'s agent (None: the whole agent's); None when there is none."""
        return self.threads.get(drone)

    def part_finished(self) -> None:
        """A drone's agent finished its part: the task ends with the last one."""
        views = [t.view for t in self.threads.values() if t.view is not None]
        if views and all(v.finished for v in views) and not self.finished:
            AgentTools.finish(self, "; ".join(f"{v.drone_id}: {v.summary or 'no summary'}"
                                              for v in views))

    def _entry(self, name: str) -> AgentThread | Outcome | None:
        """How a call of `name` runs: directly (None: it is made inside a thread, e.g. a
        batch's call), as the whole agent's thread (a route that calls the tools directly), or
        not at all (an `Outcome`: per-drone agents call only through their drone's key)."""
        if _acting.get() is not None:
            return None
        thread = self.threads.get(None)
        if thread is not None:
            return thread
        return Outcome(Status.REJECTED, f"{name} refused: this session's agents are one per "
                       "drone; call it with your drone's agent key on the session's tool routes")

    async def concurrently(self, *calls: Awaitable[Any]) -> list[Any]:
        entry = self._entry("batch")
        if entry is None:
            return await super().concurrently(*calls)
        result = entry if isinstance(entry, Outcome) else await entry.run(
            "batch", lambda: super(ServedTools, self).concurrently(*calls))
        if isinstance(result, Outcome):  # refused: the calls never run
            for call in calls:
                if inspect.iscoroutine(call):
                    call.close()
            return [result] * len(calls)
        return result

    async def close(self) -> None:
        """Cancel primitives still running, then end every thread (the task is over)."""
        await super().close()
        for thread in self.threads.values():
            thread.close()


def _threaded(name: str) -> Callable[..., Any]:
    logged = getattr(LoggedTools, name)
    if inspect.iscoroutinefunction(logged):
        @functools.wraps(logged)
        async def call_async(self: ServedTools, *args: Any, **kwargs: Any) -> Outcome:
            entry = self._entry(name)
            if entry is None:
                return cast(Outcome, await logged(self, *args, **kwargs))
            if isinstance(entry, Outcome):
                return entry
            return cast(Outcome, await entry.run(name, lambda: logged(self, *args, **kwargs)))
        return call_async

    @functools.wraps(logged)
    def call(self: ServedTools, *args: Any, **kwargs: Any) -> Outcome:
        entry = self._entry(name)
        if entry is None:
            return cast(Outcome, logged(self, *args, **kwargs))
        if isinstance(entry, Outcome):
            return entry
        return cast(Outcome, entry.sync(name, lambda: logged(self, *args, **kwargs)))
    return call


for _name in tool_names():
    setattr(ServedTools, _name, _threaded(_name))


def surface_of(tools: AgentTools, drone: str | None) -> tuple[AgentThread | None, AgentTools]:
    """The thread a caller acts as (`drone`: a drone agent's key) and what it acts on; no
    thread for a whole-agent caller (the tools run its calls as the agent's thread)."""
    if drone is None or not isinstance(tools, ServedTools):
        return None, tools
    thread = tools.thread(drone)
    if thread is None:
        raise ValueError(f"drone {drone!r} has no agent of its own in this task")
    return thread, thread.surface


async def call_tool(tools: AgentTools, drone: str | None, name: str,
                    call: Callable[[AgentTools], Awaitable[dict[str, Any]]]
                    ) -> dict[str, Any]:
    """`call(surface)` (a registry call of tool `name`) as the caller's thread; a refusal
    as its result dict."""
    thread, surface = surface_of(tools, drone)
    if thread is None:
        return await call(surface)
    result = await thread.run(name, lambda: call(surface))
    return result.to_dict() if isinstance(result, Outcome) else result


def read_tool(tools: AgentTools, drone: str | None, name: str,
              read: Callable[[AgentTools], Outcome]) -> Outcome:
    """A read tool (`read(surface)`) as the caller's thread."""
    thread, surface = surface_of(tools, drone)
    return read(surface) if thread is None else cast(Outcome, thread.sync(name,
                                                                          lambda: read(surface)))
