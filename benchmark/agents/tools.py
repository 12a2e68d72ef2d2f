"""The tools an agent acts with during one task: the gateway's primitives, counted against the
task's budget, plus `finish`.

Every primitive returns the gateway's `Outcome`. A call made after the budget is spent raises
`BudgetExhausted`; a call made after `finish` is refused. Operator resets, ground truth and the
checks are not reachable from here.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable, Sequence

from benchmark.agents.protocol import AgentTask, BudgetExhausted
from mavlink_gateway import Gateway, Outcome, Status

__all__ = ["AgentTools"]


class AgentTools:
    """One task's tool surface over a gateway. Not reusable across tasks."""

    def __init__(self, gateway: Gateway, task: AgentTask) -> None:
        self._gw = gateway
        self._budget = task.budget
        self._t0_s = gateway.services.clock_s()
        self._calls = 0
        self._in_flight: set[asyncio.Task[Outcome]] = set()
        self.finished = False
        self.summary = ""
        self.prompt_tokens = 0
        self.completion_tokens = 0
        self.cost_usd = 0.0
        self.spent: BudgetExhausted | None = None

    # ------------------------------------------------------------ accounting
    @property
    def tool_calls(self) -> int:
        return self._calls

    @property
    def sim_elapsed_s(self) -> float:
        return self._gw.services.clock_s() - self._t0_s

    @property
    def drone_ids(self) -> list[str]:
        return list(self._gw.drones)

    def add_tokens(self, prompt: int, completion: int, cost_usd: float = 0.0) -> None:
        """Token use (and its price) of the agent's model, reported in the task's record."""
        self.prompt_tokens += int(prompt)
        self.completion_tokens += int(completion)
        self.cost_usd += float(cost_usd)

    def _charge(self, name: str) -> Outcome | None:
        if self.finished:
            return Outcome(Status.REJECTED, f"{name} refused: the task is already finished")
        if self._calls >= self._budget.tool_calls:
            self.spent = BudgetExhausted(
                "tool_call_budget", f"the budget of {self._budget.tool_calls} tool calls is spent")
            raise self.spent
        if self.sim_elapsed_s >= self._budget.sim_time_s:
            self.spent = BudgetExhausted(
                "sim_time_budget",
                f"the budget of {self._budget.sim_time_s:g} simulated seconds is spent")
            raise self.spent
        self._calls += 1
        return None

    async def _call(self, name: str, make: Callable[[], Awaitable[Outcome]]) -> Outcome:
        refused = self._charge(name)
        if refused is not None:
            return refused
        task = asyncio.ensure_future(make())
        self._in_flight.add(task)
        try:
            return await asyncio.shield(task)
        finally:
            if task.done():
                self._in_flight.discard(task)

    def _sync(self, name: str, call: Callable[[], Outcome]) -> Outcome:
        refused = self._charge(name)
        return refused if refused is not None else call()

    async def close(self) -> None:
        """Cancel primitives the agent left running (the task is over)."""
        pending = [t for t in self._in_flight if not t.done()]
        for task in pending:
            task.cancel()
        if pending:
            await asyncio.gather(*pending, return_exceptions=True)
        self._in_flight.clear()

    # ----------------------------------------------------------------- tools
    def finish(self, summary: str = "") -> Outcome:
        """End the task. Scoring happens afterwards, out of the agent's sight."""
        if self.finished:
            return Outcome(Status.REJECTED, "the task is already finished")
        self.finished = True
        self.summary = str(summary)[:2000]
        return Outcome(Status.OK, "task finished")

    def list_drones(self) -> Outcome:
        def call() -> Outcome:
            states = self._gw.list_drones()
            return Outcome(Status.OK, f"{len(states)} drones",
                           data={"drones": [s.to_dict() for s in states]})
        return self._sync("list_drones", call)

    def drone_state(self, drone: str) -> Outcome:
        return self._sync("drone_state", lambda: self._gw.drone_state(drone))

    def nearby(self, drone: str) -> Outcome:
        return self._sync("nearby", lambda: self._gw.nearby(drone))

    def send_message(self, drone: str, to: str, text: str) -> Outcome:
        return self._sync("send_message", lambda: self._gw.send_message(drone, to, text))

    def broadcast(self, drone: str, text: str) -> Outcome:
        return self._sync("broadcast", lambda: self._gw.broadcast(drone, text))

    def read_messages(self, drone: str) -> Outcome:
        return self._sync("read_messages", lambda: self._gw.read_messages(drone))

    async def take_off(self, drone: str, altitude_m: float) -> Outcome:
        return await self._call("take_off", lambda: self._gw.take_off(drone, altitude_m))

    async def land(self, drone: str) -> Outcome:
        return await self._call("land", lambda: self._gw.land(drone))

    async def move_to(self, drone: str, x: float, y: float, z: float) -> Outcome:
        return await self._call("move_to", lambda: self._gw.move_to(drone, x, y, z))

    async def move_towards(self, drone: str, heading_deg: float, distance_m: float,
                           dz_m: float = 0.0) -> Outcome:
        return await self._call(
            "move_towards", lambda: self._gw.move_towards(drone, heading_deg, distance_m, dz_m))

    async def change_altitude(self, drone: str, altitude_m: float) -> Outcome:
        return await self._call("change_altitude",
                                lambda: self._gw.change_altitude(drone, altitude_m))

    async def move_along_path(self, drone: str, waypoints: Sequence[Sequence[float]]) -> Outcome:
        return await self._call("move_along_path",
                                lambda: self._gw.move_along_path(drone, waypoints))

    async def hover(self, drone: str, duration_s: float) -> Outcome:
        return await self._call("hover", lambda: self._gw.hover(drone, duration_s))

    async def rotate(self, drone: str, heading_deg: float) -> Outcome:
        return await self._call("rotate", lambda: self._gw.rotate(drone, heading_deg))

    async def return_home(self, drone: str) -> Outcome:
        return await self._call("return_home", lambda: self._gw.return_home(drone))

    async def set_home(self, drone: str) -> Outcome:
        return await self._call("set_home", lambda: self._gw.set_home(drone))

    async def take_photo(self, drone: str) -> Outcome:
        return await self._call("take_photo", lambda: self._gw.take_photo(drone))

    async def charge(self, drone: str) -> Outcome:
        return await self._call("charge", lambda: self._gw.charge(drone))
