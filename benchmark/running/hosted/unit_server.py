"""The HTTP server of one hosted session: the current task's REST API and MCP tools, reached
with that task's key.

A unit (one session and trial, wherever the backend runs it) starts one server on a free port
the first time its agent is given a task. It serves the REST app `mavswarm serve` builds
(`benchmark.server.create_app`: its tool, drone and MultiUAV-Plat routes) over a hub holding
this session alone, whose live task is swapped as tasks go, and for each task an MCP app
(`llm_tools.mcp_server`) over that task's tools. A request with the task's key reaches them
(the REST app sees an agent key of its own instead, so it never holds a task's key); a key
whose task has ended gets 410, any other key (or none) 401. Nothing else is served: no
operator or admin key exists, so the hidden checks and the whole-map views answer 403 as they
do to any agent.
"""


import asyncio
import contextlib
import contextvars
import secrets
import socket
import time
from collections.abc import AsyncIterator, Iterator
from dataclasses import dataclass
from typing import Annotated, Any

import uvicorn
from fastapi import Depends, FastAPI, HTTPException
from starlette.responses import JSONResponse, Response
from starlette.types import ASGIApp, Receive, Scope, Send

from benchmark.running.hosted.offer import TokenUse
from benchmark.server import Hub, Role, create_app
from benchmark.server.auth import API_KEY_HEADER, live_session, require
from benchmark.server.http_config import uvicorn_config
from benchmark.server.hub import Caller, LiveSession
from llm_tools.body_limit import BodyLimit
from llm_tools.input_limits import preview
from llm_tools.mcp_server import streamable_http_app
from llm_tools.registry import ToolRegistry, served_registry

__all__ = ["MCP_PATH", "TAKEN_PATH", "QuietServer", "UnitServer", "advertised_host"]

MCP_PATH = "/mcp"
TAKEN_PATH = "/taken"  # the driver says an agent took the task (POST, with the task's key)
_HEADER = API_KEY_HEADER.lower().encode("latin-1")


class QuietServer(uvicorn.Server):
    """uvicorn without its signal handlers: the run (not this server) owns Ctrl-C."""

    @contextlib.contextmanager
    def capture_signals(self) -> Iterator[None]:
        yield


def advertised_host(host: str) -> str:
    """The address agents are told to reach a server bound on `host` at."""
    if host in ("0.0.0.0", "::", ""):
        with contextlib.suppress(OSError):
            return socket.gethostbyname(socket.gethostname())
        return "127.0.0.1"
    return host


@dataclass
class _Hosted:
    """The task being served: its key and its two apps."""

    key: str
    live: LiveSession
    rest: ASGIApp
    mcp: ASGIApp
    seen: bool = False  # a request with the key has arrived
    in_flight: int = 0  # requests with the key not yet answered
    rest_in_flight: int = 0  # of which REST requests
    last_wall_s: float = 0.0  # when the last one was answered (time.monotonic)


def _add_task_routes(app: FastAPI, hub: Hub) -> None:
    """What a hosted task adds to `mavswarm serve`'s routes: token use, and MultiUAV-Plat's
    `mark-done`, which ends the task as `finish` does. They go before `serve`'s own routes of
    the same paths (the operator's `mark-done` of `benchmark.server.compat.tasks`): in a hosted
    run the agent's `mark-done` ends its task."""
    agent = require(hub, Role.AGENT)
    before = len(app.router.routes)

    @app.post("/sessions/current/tokens", tags=["tasks"],
              summary="Report the token use of the agent's model calls for this task")
    async def tokens(use: TokenUse, caller: Annotated[Caller, Depends(agent)]) -> dict[str, Any]:
        assert caller.session_id is not None
        tools = live_session(hub, caller, caller.session_id).tools
        tools.add_tokens(use.prompt, use.completion, use.cost_usd)
        return {"prompt": tools.prompt_tokens, "completion": tools.completion_tokens,
                "cost_usd": round(tools.cost_usd, 6)}

    def mark(live: LiveSession, task_id: str) -> dict[str, Any]:
        if task_id != live.task.id:
            raise HTTPException(404, f"task {preview(task_id)} is not this key's task; it "
                                f"is {live.task.id!r}")
        outcome = live.tools.finish("marked done")
        if outcome.status.value != "ok":
            raise HTTPException(409, outcome.message)
        return {"id": live.task.id, "content": live.task.text, "is_done": True,
                "status": "success", "message": outcome.message}

    @app.post("/sessions/current/tasks/{task_id}/mark-done", tags=["multiuav-plat"],
              summary="End the task (as the finish tool does)")
    def mark_current(task_id: str, caller: Annotated[Caller, Depends(agent)]
                     ) -> dict[str, Any]:
        assert caller.session_id is not None
        return mark(live_session(hub, caller, caller.session_id), task_id)

    @app.post("/sessions/{session_id}/tasks/{task_id}/mark-done", tags=["multiuav-plat"],
              summary="End the task (as the finish tool does)")
    def mark_in(session_id: str, task_id: str, caller: Annotated[Caller, Depends(agent)]
                ) -> dict[str, Any]:
        return mark(live_session(hub, caller, session_id), task_id)

    added = app.router.routes[before:]
    del app.router.routes[before:]
    app.router.routes[:0] = added


class UnitServer:
    """One session's server; tasks are served one at a time with `hosting`."""

    def __init__(self, host: str = "127.0.0.1",
                 registry: ToolRegistry | None = None) -> None:
        self.host = host
        self.url = ""
        # The tools REST and MCP serve (one registry, so both list the same tools).
        self._registry = registry or served_registry()
        self._current: _Hosted | None = None
        self._last: _Hosted | None = None
        self._retired: dict[str, str] = {}  # key -> what it was for
        # The REST app of `mavswarm serve` over this session alone, reached with a key only
        # this server knows: requests with the current task's key are passed on with it.
        self._hub = Hub()
        self._inner_key = secrets.token_urlsafe(24)
        self._inner = self._inner_key.encode("latin-1")
        self._rest: FastAPI | None = None
        self._server: QuietServer | None = None
        self._task: asyncio.Task[None] | None = None
        self.app = BodyLimit(self._dispatch)

    async def start(self) -> str:
        """Listen on a free port; the base URL agents reach it at."""
        config = uvicorn_config(self.app, host=self.host, port=0, lifespan="off",
                                timeout_graceful_shutdown=1)
        self._server = QuietServer(config)
        # In a context of its own: requests must not inherit the thread of control of the
        # task that happened to start the server (HostedTools runs them as the current one).
        self._task = asyncio.create_task(self._server.serve(), context=contextvars.Context())
        while not self._server.started:
            if self._task.done():
                self._task.result()
                raise RuntimeError(f"the hosted session's server did not start on {self.host}")
            await asyncio.sleep(0.005)
        port = self._server.servers[0].sockets[0].getsockname()[1]
        self.url = f"http://{advertised_host(self.host)}:{port}"
        return self.url

    async def close(self) -> None:
        if self._server is None or self._task is None:
            return
        self._server.should_exit = True
        with contextlib.suppress(asyncio.CancelledError):
            await self._task
        self._server = self._task = None

    def idle_s(self, key: str) -> float:
        """Wall seconds since the last request with `key` (the current task's) was answered;
        0 while one is in flight or before the first arrives."""
        current = self._current
        if current is None or current.key != key or not current.seen or current.in_flight:
            return 0.0
        return time.monotonic() - current.last_wall_s

    @contextlib.asynccontextmanager
    async def hosting(self, key: str, live: LiveSession) -> AsyncIterator[None]:
        """Serve `live`'s task to requests with `key` until the block ends; the key is dead
        from then on."""
        if self._current is not None:
            raise RuntimeError("a hosted session serves one task at a time")
        await self._drained()
        if self._rest is None:  # the REST app is built once per session, on its first task
            self._hub.add_session(live)
            self._hub.add_key(self._inner_key, Role.AGENT, live.id)
            self._rest = create_app(self._hub, self._registry)
            _add_task_routes(self._rest, self._hub)
        else:
            self._hub.sessions[live.id] = live
        mcp = streamable_http_app(self._registry, lambda: live.tools, path=MCP_PATH,
                                  host=self.host, json_response=True)
        async with mcp.router.lifespan_context(mcp):
            self._current = hosted = _Hosted(key, live, self._rest, mcp)
            try:
                yield
            finally:
                self._current = None
                self._retired[key] = f"task {live.task.id} of session {live.id}"
                self._last = hosted

    async def _drained(self, timeout_s: float = 30.0) -> None:
        """Wait until no request of the last task is still being answered: the REST app
        reads its task from the hub, so the next task goes in only once they are done (the
        episode has cancelled the primitives they waited on)."""
        last, deadline = self._last, time.monotonic() + timeout_s
        while last is not None and last.rest_in_flight and time.monotonic() < deadline:
            await asyncio.sleep(0.005)

    async def _dispatch(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            return
        key = next((v.decode("latin-1") for k, v in scope["headers"] if k == _HEADER), "")
        current = self._current
        if current is not None and key == current.key:
            current.seen = True
            path = scope["path"]
            if path == TAKEN_PATH and scope["method"] == "POST":
                current.last_wall_s = time.monotonic()  # the idle clock starts now
                await Response(status_code=204)(scope, receive, send)
                return
            is_mcp = path == MCP_PATH or path.startswith(MCP_PATH + "/")
            current.in_flight += 1
            try:
                if is_mcp:
                    await current.mcp(scope, receive, send)
                else:
                    headers = [(k, self._inner if k == _HEADER else v)
                               for k, v in scope["headers"]]
                    current.rest_in_flight += 1
                    try:
                        await current.rest({**scope, "headers": headers}, receive, send)
                    finally:
                        current.rest_in_flight -= 1
            finally:
                current.in_flight -= 1
                current.last_wall_s = time.monotonic()
            return
        if key in self._retired:
            status, detail = 410, (f"{self._retired[key]} has ended: its key no longer "
                                   "works; take the next task from the run's /next")
        elif not key:
            status, detail = 401, (f"missing API key: send the task's key (from /next) in "
                                   f"the {API_KEY_HEADER} header")
        else:
            status, detail = 401, ("unknown API key: this server takes only the key of the "
                                   "task it serves now")
        response = JSONResponse({"detail": detail}, status_code=status,
                                headers={"WWW-Authenticate": "APIKey"} if status == 401 else None)
        await response(scope, receive, send)
