"""Latency of one agent tool call through each adapter, against one live stepped swarm: the
registry called directly, the REST API over real HTTP (uvicorn on localhost, httpx client)
and MCP over Streamable HTTP (uvicorn, the official MCP client). Two calls: `drone_state`
(a read, answered from telemetry) and `take_photo` on a flying drone (a command).

    ./dev perf adapter_latency [--calls 200]
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import sys
import time
from collections.abc import AsyncIterator, Awaitable, Callable
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import httpx
from _common import pct
from mcp import Client

from agent_contract import AgentTask, AgentTools, TaskBudget
from benchmark.authoring.session_file import session_from_dict
from benchmark.running.episode import swarm_gateway
from benchmark.server import Hub, LiveSession, Role, create_app
from benchmark.server.serve import serve_asgi
from llm_tools import default_registry
from llm_tools.mcp_server import streamable_http_app
from tests.bench_fixtures import small_session

KEY = "bench-agent"


def _ms(samples: list[float]) -> str:
    return f"p50 {pct(samples, 50) * 1000:7.3f} ms  p95 {pct(samples, 95) * 1000:7.3f} ms"


@contextlib.asynccontextmanager
async def _served(app: Any) -> AsyncIterator[str]:
    ready: asyncio.Future[str] = asyncio.get_running_loop().create_future()
    task = asyncio.create_task(serve_asgi(app, host="127.0.0.1", port=0,
                                          on_ready=ready.set_result))
    await asyncio.wait({task, ready}, return_when=asyncio.FIRST_COMPLETED)
    if task.done():
        task.result()
    try:
        yield ready.result()
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task


async def _time(call: Callable[[], Awaitable[dict[str, Any]]], calls: int) -> list[float]:
    await call()  # warm-up (connections, first-call imports)
    samples = []
    for _ in range(calls):
        t = time.perf_counter()
        result = await call()
        samples.append(time.perf_counter() - t)
        if result.get("status") != "ok":
            raise RuntimeError(f"benchmark call failed: {result}")
    return samples


async def main(calls: int) -> None:
    data = small_session(["takeoff_hold"])
    session = session_from_dict(data, source="bench")
    task = session.tasks[0]
    registry = default_registry()
    async with swarm_gateway(session) as (swarm, services, gateway):
        tools = AgentTools(gateway, AgentTask(session.id, task.id, task.text,
                                              TaskBudget(20 * calls + 100, 1e9)))
        drone = tools.drone_ids[0]
        took_off = await registry.call(tools, "take_off", {"drone_id": drone, "altitude_m": 10})
        if took_off["status"] != "ok":
            raise RuntimeError(f"take_off failed: {took_off}")
        hub = Hub()
        hub.add_session(LiveSession(session, task, swarm, services, gateway, tools,
                                    services.clock_s()))
        hub.add_key(KEY, Role.AGENT, session.id)
        args = {"drone_id": drone}
        async with (_served(create_app(hub, registry)) as rest_url,
                    _served(streamable_http_app(registry, lambda: tools)) as mcp_url,
                    httpx.AsyncClient(base_url=rest_url, headers={"X-API-Key": KEY}) as http,
                    Client(f"{mcp_url}/mcp") as mcp):

            async def via_rest(name: str) -> dict[str, Any]:
                r = await http.post(f"/sessions/{session.id}/tools/{name}", json=args)
                return dict(r.json())

            async def via_mcp(name: str) -> dict[str, Any]:
                return dict((await mcp.call_tool(name, args)).structured_content or {})

            adapters: dict[str, Callable[[str], Awaitable[dict[str, Any]]]] = {
                "registry": lambda name: registry.call(tools, name, args),
                "rest/http": via_rest,
                "mcp/http": via_mcp,
            }
            print(f"{calls} calls each, one stepped swarm of {len(tools.drone_ids)} drones")
            for name in ("drone_state", "take_photo"):
                for adapter, call in adapters.items():
                    samples = await _time(lambda c=call, n=name: c(n), calls)
                    print(f"{name:<12} {adapter:<9} {_ms(samples)}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=200)
    asyncio.run(main(parser.parse_args().calls))
