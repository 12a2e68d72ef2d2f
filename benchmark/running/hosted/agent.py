"""The agent of a hosted run: `ExternalAgent` runs in a unit like any in-process agent, and
instead of deciding anything it publishes each task and serves that task's very tools to an
agent outside the process until the task ends.

Because the episode runs it as it runs every agent (`benchmark.running.episode.run_session`), a
hosted
task is reset, clocked, recorded, evaluated, resumed and reported exactly as an in-process
agent's: records carry the agent name ``external`` (a fixed name, so a resumed run finds its
records whoever connects). A task ends when the agent calls `finish` (or MultiUAV-Plat's
`mark-done`), when a call finds the budget spent, or when the agent has made no request for
`idle_timeout_s` wall seconds after its first one (then an ``agent_error``). A task offered
but not yet taken waits for an agent as long as it takes; with a lockstep clock nothing moves
meanwhile.
"""

from __future__ import annotations

import asyncio
import contextlib
import multiprocessing
import secrets
from typing import cast
from urllib.parse import quote

from agent_contract import AgentTask, AgentTools
from benchmark.authoring.session_file import Session
from benchmark.running.backends import Handle
from benchmark.running.hosted import EXTERNAL
from benchmark.running.hosted.offer import BudgetView, Notice, NoticeKind, TaskOffer
from benchmark.running.hosted.task_tools import HostedTools
from benchmark.running.hosted.unit_server import MCP_PATH, UnitServer
from benchmark.server.hub import LiveSession
from emulator.services import SwarmServices
from emulator.swarm import Swarm
from mavlink_gateway import Gateway
from mavlink_gateway.pacing import current_thinker

__all__ = ["EXTERNAL", "IDLE_TIMEOUT_S", "AgentGone", "ExternalAgent"]

IDLE_TIMEOUT_S = 600.0
"""A taken task whose agent makes no request for this long ends as an agent error."""
UNBOUNDED_WALL_S = 10 * 365 * 86_400.0
"""The episode's wall limit for a hosted task: none that matters, since a task may wait for
an agent to take it as long as it takes; `idle_timeout_s` bounds a taken one."""


class AgentGone(Exception):
    """The external agent stopped making requests on a task it had taken."""


def _world(tools: AgentTools) -> tuple[Gateway, SwarmServices, Swarm]:
    """The gateway, services and swarm the episode bound `tools` to. The hosted agent is the
    benchmark's side of the wire: its REST routes read the world as `mavswarm serve`'s do
    (perception and compatibility views), so it needs what the episode holds; the agent
    outside sees only what those routes show an agent key."""
    gateway = cast(Gateway, tools._gw)
    services = cast(SwarmServices, gateway.services)
    return gateway, services, services._swarm


class ExternalAgent:
    """Serves one session's tasks to an agent outside the process (see the module doc).
    Use as an async context manager around the session: its server closes on exit."""

    name = EXTERNAL

    def __init__(self, session: Session, send: Handle, *, trial: int = 0,
                 host: str = "127.0.0.1", idle_timeout_s: float = IDLE_TIMEOUT_S) -> None:
        self._session = session
        self._send = send
        self._trial = trial
        self._idle_timeout_s = idle_timeout_s
        self._server = UnitServer(host)
        self._started = False

    async def __aenter__(self) -> ExternalAgent:
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self._server.close()
        self._notify(Notice(kind=NoticeKind.CLOSED))

    def _notify(self, notice: Notice) -> None:
        self._send(("hosted", notice.model_dump(mode="json")))

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        if not self._started:
            await self._server.start()
            self._started = True
        spec = next(t for t in self._session.tasks if t.id == task.task_id)
        gateway, services, swarm = _world(tools)
        key = secrets.token_urlsafe(18)
        ended = asyncio.Event()
        told = False

        def end() -> None:  # once, in the loop's thread, before the ending call answers
            nonlocal told
            if not told:
                told = True
                self._notify(Notice(kind=NoticeKind.ENDED, key=key))
            ended.set()

        hosted = HostedTools(tools, current_thinker(), end, lockstep=services.lockstep)
        live = LiveSession(self._session, spec, swarm, services, gateway,
                           cast(AgentTools, hosted), services.clock_s())
        url = self._server.url
        offer = TaskOffer(session=task.session_id, task_id=task.task_id, trial=self._trial,
                          text=task.text, budget=BudgetView(tool_calls=task.budget.tool_calls,
                                                            sim_time_s=task.budget.sim_time_s),
                          drones=list(gateway.drones), key=key, base_url=url,
                          tools_url=f"{url}/sessions/{quote(task.session_id, safe='')}/tools",
                          mcp_url=f"{url}{MCP_PATH}")
        try:
            async with self._server.hosting(key, live):
                self._notify(Notice(kind=NoticeKind.OFFER, key=key, offer=offer))
                gone = await self._until_over(ended, hosted, key)
        finally:
            end()
        # Raised out here: inside, the MCP app's task group would wrap them.
        if gone == "orphaned":
            raise SystemExit("the driver of this hosted run is gone; nothing can record "
                             "this session's results")
        if gone == "silent":
            raise AgentGone(f"the external agent made no request for "
                            f"{self._idle_timeout_s:g} s after taking the task")

    async def _until_over(self, ended: asyncio.Event, hosted: HostedTools, key: str
                          ) -> str | None:
        """Wait for the task's end; "silent" when its agent stopped making requests
        instead, "orphaned" when this unit runs in a worker process whose driver died (a
        hosted task would wait for an agent forever)."""
        driver = multiprocessing.parent_process()
        while not ended.is_set() and not hosted.over:
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(ended.wait(), 1.0)
            if self._server.idle_s(key) > self._idle_timeout_s:
                return "silent"
            if driver is not None and not driver.is_alive():
                return "orphaned"
        return None
