"""A console served in-process for browser tests (uvicorn on a free port, in a loop thread):
`serve_console(state)` yields its base URL; `swarm_with_console(spots, key)` yields a running
swarm (5x real time) with the console of `up --web`, and its URL."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Iterator, Sequence
from dataclasses import replace

from benchmark.server.serve import serve_asgi
from console.app import ConsoleState, create_console_app
from console.cli import swarm_console
from emulator.clock import ClockConfig
from emulator.scenario import default_scenario
from emulator.swarm import PortPlan, Swarm
from tests.browser_fixtures import LoopThread
from tests.ports import unused_tcp_port, unused_udp_port

__all__ = ["serve_console", "swarm_with_console"]


@contextlib.contextmanager
def swarm_with_console(spots: Sequence[tuple[float, float]], key: str
                       ) -> Iterator[tuple[Swarm, str]]:
    """A swarm of one drone on the ground at each of `spots`, 5x real time, with the console
    of `up --web` opened by operator key `key`; yields (the swarm, the console's URL)."""
    base = default_scenario(len(spots))
    vehicles = tuple(replace(v, position_m=(x, y, 0.0), home_m=(x, y, 0.0))
                     for v, (x, y) in zip(base.vehicles, spots, strict=True))
    scenario = replace(base, vehicles=vehicles)
    loop = LoopThread()
    stack = contextlib.AsyncExitStack()

    async def start() -> tuple[Swarm, str]:
        ports = PortPlan(bind_host="127.0.0.1", bind_port=unused_udp_port(), api_port=0,
                         gcs_port=0)
        swarm = await stack.enter_async_context(
            Swarm(scenario, clock=ClockConfig(speed=5.0), ports=ports))
        ready: asyncio.Future[str] = asyncio.get_running_loop().create_future()
        await stack.enter_async_context(swarm_console(
            swarm, port=unused_tcp_port(), key=key,
            on_ready=lambda url, _key: ready.set_result(url)))
        return swarm, await asyncio.wait_for(ready, 30)

    try:
        yield loop.run(start())
    finally:
        loop.run(stack.aclose())
        loop.close()


@contextlib.contextmanager
def serve_console(state: ConsoleState, loop: LoopThread | None = None) -> Iterator[str]:
    """Serve `state`'s console on 127.0.0.1 (a free port) while inside; yields its URL."""
    own = loop is None
    thread = loop or LoopThread()
    app = create_console_app(state)
    server: list[asyncio.Task[None]] = []

    async def start() -> str:
        ready: asyncio.Future[str] = asyncio.get_running_loop().create_future()
        server.append(asyncio.create_task(
            serve_asgi(app, host="127.0.0.1", port=0, on_ready=ready.set_result)))
        return await asyncio.wait_for(asyncio.shield(ready), 30)

    async def stop() -> None:
        for task in server:
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task
        await state.aclose()

    try:
        yield thread.run(start())
    finally:
        thread.run(stop())
        if own:
            thread.close()
