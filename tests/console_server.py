"""A console served in-process for browser tests (uvicorn on a free port, in a loop thread):
`serve_console(state)` yields its base URL."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Iterator

from benchmark.server.serve import serve_asgi
from console.app import ConsoleState, create_console_app
from tests.browser_fixtures import LoopThread

__all__ = ["serve_console"]


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
