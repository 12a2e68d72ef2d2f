"""The web console as `mavswarm serve` mounts it (under /console, on the REST API's app) over a
real stepped swarm in-process (httpx ASGITransport), with agent, operator and admin keys; by
default a world without tasks, so operator commands and link changes are taken."""

from __future__ import annotations

import contextlib
from collections.abc import AsyncIterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx

from agent_contract import AgentTask, AgentTools
from benchmark.authoring.session_file import session_from_dict
from benchmark.running.episode import swarm_gateway
from benchmark.server import Hub, LiveSession, Role, create_app
from benchmark.server.session_runner import first_task
from console.cli import console_for_hub
from tests.bench_fixtures import small_session
from tests.rest_fixtures import KEYS

__all__ = ["KEYS", "ConsoleServed", "console_served"]


@dataclass
class ConsoleServed:
    client: httpx.AsyncClient
    hub: Hub
    live: LiveSession
    app: Any


@contextlib.asynccontextmanager
async def console_served(*, data: dict[str, Any] | None = None,
                         session_dirs: tuple[Path, ...] = ()) -> AsyncIterator[ConsoleServed]:
    """`serve` of one session (default: a generated world without tasks) with the console at
    /console; `session_dirs` are the server's --session-dir folders."""
    data = data or small_session([])
    session = session_from_dict(data, source="s.json")
    task = first_task(session)
    assert task.budget is not None
    async with swarm_gateway(session) as (swarm, services, gateway):
        tools = AgentTools(gateway, AgentTask(session.id, task.id, task.text, task.budget))
        live = LiveSession(session, task, swarm, services, gateway, tools, services.clock_s())
        hub = Hub()
        hub.add_session(live)
        for name, key in KEYS.items():
            hub.add_key(key, Role(name), session.id if name == "agent" else None)
        app = create_app(hub)
        console_for_hub(app, hub, [], session_dirs=session_dirs)
        transport = httpx.ASGITransport(app=app)
        async with httpx.AsyncClient(transport=transport, base_url="http://serve") as client:
            yield ConsoleServed(client, hub, live, app)
