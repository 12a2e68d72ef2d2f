"""The hosted run's endpoint, served by the driver: `GET /next` hands out tasks, `GET /status`
counts them, and MultiUAV-Plat clients play through the reference routes with a seat key.

A seat key stands for one reference client that knows a single base URL and key: its
`GET /sessions/current/tasks/next` takes a task (or answers the one it holds, until that task
ends), every other route is passed on to that task's server with the task's key, and
`POST /sessions/current/tasks/{id}/mark-done` ends the task there. The run issues one seat key
per session it hosts at once (`--workers`).
"""


import asyncio
import contextlib
import re
import secrets
import socket
import threading
from collections.abc import AsyncIterator, Callable
from typing import Annotated, Any

import httpx
from fastapi import FastAPI, HTTPException, Query, Request
from fastapi.responses import JSONResponse, Response

from benchmark.running.hosted.board import AllOut, Board, NotYet
from benchmark.running.hosted.offer import TaskOffer
from benchmark.running.hosted.unit_server import TAKEN_PATH, QuietServer
from benchmark.server.auth import API_KEY_HEADER
from benchmark.server.http_config import uvicorn_config
from llm_tools.body_limit import BodyLimit

__all__ = ["DEFAULT_WAIT_S", "Endpoint", "Seats", "endpoint_app"]

DEFAULT_WAIT_S = 20.0
MAX_WAIT_S = 300.0
_MARK_DONE = re.compile(r"^sessions/[^/]+/tasks/[^/]+/mark-done$")


class Seats:
    """The seat keys of reference clients and the task each holds."""

    def __init__(self, count: int) -> None:
        self.keys = [f"seat-{secrets.token_urlsafe(12)}" for _ in range(count)]
        self.held: dict[str, TaskOffer | None] = dict.fromkeys(self.keys)
        self._locks: dict[str, asyncio.Lock] = {}

    def lock(self, seat: str) -> asyncio.Lock:
        return self._locks.setdefault(seat, asyncio.Lock())

    def seat_of(self, request: Request) -> str:
        key = request.headers.get(API_KEY_HEADER, "")
        if key in self.held:
            return key
        if not key:
            raise HTTPException(401, f"missing API key: MultiUAV-Plat clients send one of the "
                                f"run's seat keys in the {API_KEY_HEADER} header; other "
                                "agents take tasks with GET /next")
        raise HTTPException(401, "unknown API key: the endpoint takes seat keys (printed when "
                            "the run starts); a task's key goes to that task's base_url")


def _json(status: int, detail: str, **headers: str) -> JSONResponse:
    return JSONResponse({"detail": detail}, status_code=status, headers=headers or None)


async def _take(board: Board, wait_s: float, http: httpx.AsyncClient
                ) -> TaskOffer | JSONResponse | None:
    try:
        offer = await board.take(wait_s)
    except AllOut as error:
        return _json(409, str(error))
    except NotYet as error:
        return _json(503, str(error), **{"Retry-After": "0"})
    if offer is not None:  # the unit starts the task's idle clock (a taken task left alone)
        task = asyncio.create_task(_tell_taken(http, offer))
        _telling.add(task)
        task.add_done_callback(_telling.discard)
    return offer


_telling: set[asyncio.Task[None]] = set()


async def _tell_taken(http: httpx.AsyncClient, offer: TaskOffer) -> None:
    with contextlib.suppress(httpx.HTTPError):
        await http.post(f"{offer.base_url}{TAKEN_PATH}", headers={API_KEY_HEADER: offer.key})


def endpoint_app(board: Board, seats: Seats) -> FastAPI:
    clients: list[httpx.AsyncClient] = []

    @contextlib.asynccontextmanager
    async def lifespan(_: FastAPI) -> AsyncIterator[None]:
        async with httpx.AsyncClient(timeout=None) as client:
            clients.append(client)
            yield

    def http() -> httpx.AsyncClient:
        return clients[0]

    app = FastAPI(title="mavswarm hosted run", openapi_url=None, docs_url=None, redoc_url=None,
                  lifespan=lifespan)
    app.add_middleware(BodyLimit)

    wait = Query(ge=0.0, le=MAX_WAIT_S,
                 description="seconds to wait for a task before answering 503")

    @app.get("/next", summary="Take the next task (200), or 204 once the run is over")
    async def next_task(wait_s: Annotated[float, wait] = DEFAULT_WAIT_S) -> Response:
        taken = await _take(board, wait_s, http())
        if isinstance(taken, JSONResponse):
            return taken
        if taken is None:
            return Response(status_code=204)
        return JSONResponse(taken.model_dump(mode="json"))

    @app.get("/status", summary="How many tasks are on offer and out; whether the run is over")
    def status() -> dict[str, Any]:
        return board.counts()

    @app.get("/sessions/current/tasks/next", tags=["multiuav-plat"],
             summary="A seat's task: the one it holds, else the next one")
    async def seat_next(request: Request,
                        wait_s: Annotated[float, wait] = DEFAULT_WAIT_S) -> Response:
        seat = seats.seat_of(request)
        async with seats.lock(seat):  # one task per seat, however many ask at once
            held = seats.held[seat]
            if held is None or not board.is_out(held.key):
                taken = await _take(board, wait_s, http())
                if isinstance(taken, JSONResponse):
                    return taken
                if taken is None:
                    seats.held[seat] = None
                    return _json(404, "no task is left: the hosted run is over")
                seats.held[seat] = held = taken
        return JSONResponse({"id": held.task_id, "content": held.text})

    @app.api_route("/{path:path}", methods=["GET", "POST", "PUT", "PATCH", "DELETE"],
                   tags=["multiuav-plat"], summary="Passed on to the seat's task")
    async def seat_route(path: str, request: Request) -> Response:
        if path in ("next", "status"):
            return _json(405, f"/{path} answers GET only", Allow="GET")
        seat = seats.seat_of(request)
        held = seats.held[seat]
        if held is None or not board.is_out(held.key):
            seats.held[seat] = None
            return _json(409, "this seat holds no task now: GET /sessions/current/tasks/next "
                              "first")
        headers = {API_KEY_HEADER: held.key}
        if "content-type" in request.headers:
            headers["content-type"] = request.headers["content-type"]
        try:
            answer = await http().request(request.method, f"{held.base_url}/{path}",
                                          params=request.query_params,
                                          content=await request.body(), headers=headers)
        except httpx.TransportError:
            answer = None
        if answer is None or answer.status_code == 410:
            seats.held[seat] = None
            return _json(410, f"task {held.task_id} of session {held.session} has ended; GET "
                              "/sessions/current/tasks/next for the next one")
        if answer.status_code == 200 and request.method == "POST" and _MARK_DONE.match(path):
            seats.held[seat] = None
            board.ended(held.key)
        return Response(answer.content, status_code=answer.status_code,
                        media_type=answer.headers.get("content-type"))

    return app


class Endpoint:
    """The endpoint served from a thread of the driver, so the run itself goes on in the
    main thread as for any agent."""

    def __init__(self, board: Board, seats: Seats, *, host: str, port: int) -> None:
        self._board, self._seats = board, seats
        self._sock = socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET)
        self._sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            self._sock.bind((host, port))  # a clear OSError here when the port is taken
        except OSError as error:
            self._sock.close()
            raise OSError(f"the hosted run cannot listen on {host}:{port}: "
                          f"{error.strerror or error}") from None
        self.port = int(self._sock.getsockname()[1])
        self._server: QuietServer | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._ready = threading.Event()
        self._failed: BaseException | None = None
        self._thread = threading.Thread(target=self._main, name="hosted-endpoint", daemon=True)

    def start(self, timeout_s: float = 30.0) -> None:
        self._thread.start()
        if not self._ready.wait(timeout_s) or self._failed is not None:
            raise OSError(f"the hosted run's endpoint did not start: {self._failed}")

    def stop(self) -> None:
        server, loop = self._server, self._loop
        if server is not None and loop is not None and self._thread.is_alive():
            loop.call_soon_threadsafe(setattr, server, "should_exit", True)
            self._thread.join(timeout=10.0)
        self._sock.close()

    def _main(self) -> None:
        try:
            asyncio.run(self._serve())
        except BaseException as error:  # reported to start(); nothing else listens here
            self._failed = error
            self._ready.set()

    async def _serve(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._board.bind(self._loop)
        config = uvicorn_config(endpoint_app(self._board, self._seats), lifespan="on",
                                timeout_graceful_shutdown=1)
        self._server = QuietServer(config)
        task = asyncio.create_task(self._server.serve(sockets=[self._sock]))
        while not self._server.started and not task.done():
            await asyncio.sleep(0.005)
        self._ready.set()
        await task


def on_hosted(board: Board) -> Callable[[tuple[str, Any]], None]:
    """The driver's handler of units' ``("hosted", notice)`` messages."""

    def handle(message: tuple[str, Any]) -> None:
        kind, payload = message
        if kind == "hosted":
            board.post(payload)

    return handle
