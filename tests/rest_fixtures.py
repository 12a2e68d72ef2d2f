"""One live session served over the REST API in-process (httpx ASGITransport) on a real
stepped swarm, with an agent, an operator and an admin key."""

from __future__ import annotations

import contextlib
from collections.abc import AsyncIterator
from dataclasses import dataclass
from typing import Any

import httpx

from agent_contract import AgentTask, AgentTools, TaskBudget
from benchmark.authoring.session_file import session_from_dict
from benchmark.running.episode import swarm_gateway
from benchmark.server import Hub, LiveSession, Role, create_app
from tests.bench_fixtures import small_session

__all__ = ["KEYS", "Served", "as_role", "served"]

KEYS = {"agent": "key-agent", "operator": "key-operator", "admin": "key-admin"}


def as_role(role: str) -> dict[str, str]:
    """The headers of a request made with `role`'s key."""
    return {"X-API-Key": KEYS[role]}


@dataclass
class Served:
    client: httpx.AsyncClient
    hub: Hub
    live: LiveSession
    data: dict[str, Any]


@contextlib.asynccontextmanager
async def served(*, role: str | None = None,
                 data: dict[str, Any] | None = None) -> AsyncIterator[Served]:
    """A session with one take-off task (budget 200 calls, 600 s), or `data`; `role` makes
    the client send that role's key by default."""
    data = data or small_session(["takeoff_hold"])
    session = session_from_dict(data, source="s.json")
    task = session.tasks[0]
    async with swarm_gateway(session) as (swarm, services, gateway):
        tools = AgentTools(gateway, AgentTask(session.id, task.id, task.text,
                                              TaskBudget(200, 600.0)))
        live = LiveSession(session, task, swarm, services, gateway, tools, services.clock_s())
        hub = Hub()
        hub.add_session(live)
        for name, key in KEYS.items():
            hub.add_key(key, Role(name), session.id if name == "agent" else None)
        transport = httpx.ASGITransport(app=create_app(hub))
        headers = as_role(role) if role else None
        async with httpx.AsyncClient(transport=transport, base_url="http://rest",
                                     headers=headers) as client:
            yield Served(client, hub, live, data)
