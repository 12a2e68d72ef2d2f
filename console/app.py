"""The console's HTTP and WebSocket routes (a FastAPI app, mounted at the root by `replay` and
`up --web`, under `/console` by `serve`).

Pages (one HTML page; the script picks the view from the path): `/` (home), `/live/{id}`,
`/runs`, `/runs/{run}`, `/inspect/{session}/{task}?trial=K[&run=R][&agent=A]`, `/compare`,
`/replay` (a truth file), `/editor`. Data under `/api/...`; live frames over the WebSocket
`/api/live/{id}/ws?key=KEY`; a live swarm's link faults at `/api/live/{id}/link-faults` and
`/api/live/{id}/vehicles/{drone}/link` (benchmark.server.link_routes). Every API route needs
an operator or admin key (`X-API-Key` header or `key` query parameter) unless the console was
opened for local files only (console.auth: 401, 403; the WebSocket closes with 4401, 4403,
4404). Bodies are bounded and parsed as on the agent surfaces (llm_tools.body_limit: 413 over
1 MiB, 422 naming the field); session files are read from the session folders only
(benchmark.authoring.session_folders). The editor's task and template routes are
console.task_editor_routes.

`/leaderboard` ranks every (run, agent) served (`/api/leaderboard`, with intervals);
`/api/compare?a=RUN&b=RUN` pairs two of them (benchmark.reporting.compare) for the compare view.
"""


import asyncio
import json
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Annotated, Any

from fastapi import Depends, FastAPI, HTTPException, Query, Request, WebSocket
from fastapi.responses import HTMLResponse, JSONResponse, Response
from starlette.concurrency import run_in_threadpool
from starlette.websockets import WebSocketDisconnect

from benchmark.authoring.session_folders import SessionFolders, SessionPathError
from benchmark.server.link_routes import LinkTarget, add_link_api
from console.auth import ConsoleAuth, close_code
from console.editor import (
    EditorError,
    blank_session,
    editable_session,
    generated_session,
    save_session,
    start_choices,
    validate_session,
)
from console.editor_routes import add_editor_routes
from console.live import LiveFeed, LiveSwarm
from console.live_routes import add_live_routes
from console.request_bodies import EditorSaveBody
from console.results_index import ReplayIndex
from console.task_editor_routes import add_task_editor_routes
from console.task_proof import ProofRunner
from llm_tools.body_limit import bound_inputs, json_body
from llm_tools.input_limits import MAX_SESSION_NUMBER_ABS

__all__ = ["ConsoleState", "create_console_app"]

PAGES = ("/", "/live/{rest:path}", "/runs", "/runs/{rest:path}", "/inspect/{rest:path}",
         "/compare", "/leaderboard", "/replay", "/editor")
ASSETS = {"app.js": "text/javascript", "style.css": "text/css"}
_CLOSE_REASON_BYTES = 123
session_body = json_body(max_number_abs=MAX_SESSION_NUMBER_ABS)


@dataclass
class ConsoleState:
    """What one console serves."""

    auth: ConsoleAuth
    lives: dict[str, LiveSwarm] = field(default_factory=dict)
    index: ReplayIndex = field(default_factory=ReplayIndex)
    editor_root: Path = field(default_factory=Path.cwd)
    session_folders: SessionFolders = field(default_factory=SessionFolders)
    """Where the editor opens session files (the editor's save folder is added to them)."""
    feeds: dict[str, LiveFeed] = field(default_factory=dict)
    rate_hz: float = 10.0
    refresh: Callable[[], None] | None = None
    """Called before live swarms are looked up (sessions a server starts later)."""

    proofs: ProofRunner = field(init=False)
    """The editor's oracle proofs (console.task_proof): each a live swarm while it flies."""

    def __post_init__(self) -> None:
        self.session_folders.allow_folder(self.editor_root)
        self.proofs = ProofRunner(self.lives, self.forget_feed)

    def forget_feed(self, live_id: str) -> None:
        """Stop and drop the frame feed of a live swarm that is gone."""
        feed = self.feeds.pop(live_id, None)
        if feed is not None:
            asyncio.get_running_loop().create_task(feed.aclose())

    def live_swarms(self) -> dict[str, LiveSwarm]:
        if self.refresh is not None:
            self.refresh()
        return self.lives

    def feed(self, live_id: str) -> LiveFeed:
        if live_id not in self.feeds:
            self.feeds[live_id] = LiveFeed(self.lives[live_id], self.rate_hz)
        return self.feeds[live_id]

    async def aclose(self) -> None:
        await self.proofs.aclose()
        for feed in self.feeds.values():
            await feed.aclose()


def _asset(name: str) -> bytes:
    path = resources.files("console") / "static" / name
    try:
        return path.read_bytes()
    except FileNotFoundError:
        raise HTTPException(500, f"console/static/{name} is missing: the page was not built "
                                 "(run ./dev, or `npm ci && npm run build` in console/web)"
                            ) from None


def _close_reason(text: str) -> str:
    """`text` cut to what a WebSocket close frame carries (123 bytes of UTF-8)."""
    return text.encode("utf-8", "replace")[:_CLOSE_REASON_BYTES].decode("utf-8", "ignore")


def create_console_app(state: ConsoleState, *, base: str = "") -> FastAPI:
    """The console app; `base` is the path it is mounted at ("" for the root)."""
    app = FastAPI(title="mavswarm console", openapi_url=None, docs_url=None, redoc_url=None)
    bound_inputs(app)

    def staff(request: Request) -> str:
        verdict = state.auth.check_connection(request)
        if verdict.role is None:
            raise HTTPException(verdict.status, verdict.reason)
        return verdict.role

    Staff = Annotated[str, Depends(staff)]
    config = json.dumps({"base": base, "open": state.auth.open_access})

    def page() -> HTMLResponse:
        html = _asset("index.html").decode("utf-8").replace("__CONSOLE_CONFIG__", config)
        return HTMLResponse(html.replace("__BASE__", base))

    for route in PAGES:
        app.add_api_route(route, page, methods=["GET"], response_class=HTMLResponse)

    @app.get("/favicon.ico")
    def favicon() -> Response:
        return Response(status_code=204)

    @app.get("/static/{name}")
    def asset(name: str) -> Response:
        if name not in ASSETS:
            raise HTTPException(404, f"no asset {name!r}")
        return Response(_asset(name), media_type=ASSETS[name],
                        headers={"Cache-Control": "no-cache"})

    @app.get("/api/info")
    def info(role: Staff) -> dict[str, Any]:
        return {"role": role,
                "live": [{"id": live.id, "name": live.name, "drones": len(live.scene["drones"]),
                          "commands": live.commander is not None}
                         for live in state.live_swarms().values()],
                "runs": [run.summary() for run in state.index.runs.values()],
                "truth": None if state.index.truth is None else state.index.truth.path.name}

    def live_or_404(live_id: str) -> LiveSwarm:
        if live_id not in state.live_swarms():
            raise HTTPException(404, f"no live swarm {live_id!r}; live: "
                                     f"{', '.join(state.lives) or 'none'}")
        return state.lives[live_id]

    @app.get("/api/live/{live_id}/scene")
    def scene(live_id: str, role: Staff) -> dict[str, Any]:
        live = live_or_404(live_id)
        return {"id": live.id, "name": live.name, "world": live.scene,
                "task": live.task_text, "commands": live.commander is not None}

    @app.websocket("/api/live/{live_id}/ws")
    async def live_ws(websocket: WebSocket, live_id: str) -> None:
        verdict = state.auth.check_connection(websocket)
        status, reason = verdict.status, verdict.reason
        if verdict.role is not None and live_id not in state.live_swarms():
            status, reason = 404, f"no live swarm {live_id[:40]!r}"
        await websocket.accept()
        if status != 200:  # accepted, then closed: a browser reads the code and reason
            await websocket.close(code=close_code(status), reason=_close_reason(reason))
            return
        feed = state.feed(live_id)
        queue = feed.subscribe()
        try:
            while True:
                await websocket.send_text(await queue.get())
        except (WebSocketDisconnect, RuntimeError, OSError):
            pass
        finally:
            feed.unsubscribe(queue)

    add_live_routes(app, state, staff)
    add_editor_routes(app, staff)
    add_task_editor_routes(app, state, staff)

    def link_target(live_id: str, role: str) -> LinkTarget:
        live = live_or_404(live_id)
        if live.links is None:
            raise HTTPException(409, f"live swarm {live_id!r} runs elsewhere: its links are "
                                     "not changed from here")
        return live.links(role)

    add_link_api(app, "/api/live/{session_id}", staff, link_target, "links")

    def run_or_404(run_id: str):
        if run_id not in state.index.runs:
            raise HTTPException(404, f"no results run {run_id!r}; runs: "
                                     f"{', '.join(state.index.runs) or 'none'}")
        return state.index.runs[run_id]

    @app.get("/api/runs/{run_id}/tasks")
    def run_tasks(run_id: str, role: Staff) -> dict[str, Any]:
        run = run_or_404(run_id)
        return {**run.summary(), "rows": run.rows()}

    @app.get("/api/task/{session_id}/{task_id}")
    def task(session_id: str, task_id: str, role: Staff, trial: int = 0,
             run: Annotated[str | None, Query()] = None,
             agent: Annotated[str | None, Query()] = None) -> dict[str, Any]:
        runs = [run_or_404(run)] if run is not None else list(state.index.runs.values())
        for candidate in runs:
            record = candidate.find(session_id, task_id, trial, agent)
            if record is not None:
                return candidate.task_view(record)
        raise HTTPException(404, f"no record of task {task_id!r} of session {session_id!r} "
                                 f"(trial {trial}) in runs {', '.join(r.id for r in runs)}")

    @app.get("/api/leaderboard")
    def leaderboard(role: Staff) -> dict[str, Any]:
        try:
            return {"rows": state.index.leaderboard()}
        except ValueError as error:
            raise HTTPException(400, str(error)) from None

    @app.get("/api/compare")
    def compare(a: str, b: str, role: Staff) -> dict[str, Any]:
        try:
            return state.index.compare(a, b)
        except KeyError as error:
            raise HTTPException(404, str(error.args[0])) from None
        except ValueError as error:
            raise HTTPException(400, str(error)) from None

    @app.get("/api/truth")
    def truth(role: Staff) -> dict[str, Any]:
        if state.index.truth is None:
            raise HTTPException(404, "no truth file was opened")
        return state.index.truth.view()

    @app.get("/api/editor/choices")
    def editor_choices(role: Staff) -> dict[str, Any]:
        return start_choices()

    @app.get("/api/editor/start")
    def editor_start(role: Staff, source: str = "blank", path: str = "", family: str = "",
                     level: str = "", index: int = 1) -> dict[str, Any]:
        try:
            if source == "blank":
                return blank_session()
            if source == "file":  # a worker thread: FastAPI runs a plain def route in one
                found, data = state.session_folders.read(path)
                return editable_session(data, str(found))
            if source == "level":
                return generated_session(family, level, index)
        except SessionPathError as error:
            raise HTTPException(error.http_status, str(error)) from None
        except ValueError as error:
            raise HTTPException(422, str(error)) from None
        raise HTTPException(422, f"source must be blank, file or level, got {source[:20]!r}")

    @app.post("/api/editor/open")
    def editor_open(role: Staff, body: Annotated[Any, Depends(session_body)]
                    ) -> dict[str, Any]:
        """An uploaded session file (the body: mavswarm or MultiUAV-Plat JSON) to edit."""
        try:
            return editable_session(body, "the uploaded session")
        except ValueError as error:
            raise HTTPException(422, str(error)) from None

    @app.post("/api/editor/validate")
    async def editor_validate(role: Staff, body: Annotated[Any, Depends(session_body)]
                              ) -> JSONResponse:
        try:
            return JSONResponse(validate_session(body))
        except ValueError as error:
            failure = error if isinstance(error, EditorError) else EditorError(str(error))
            return JSONResponse(failure.to_json(), status_code=422)

    @app.post("/api/editor/save")
    async def editor_save(role: Staff, body: Annotated[EditorSaveBody, Depends(json_body(
            EditorSaveBody, max_number_abs=MAX_SESSION_NUMBER_ABS))]) -> JSONResponse:
        try:
            saved = await run_in_threadpool(save_session, body.session, Path(body.path),
                                            state.editor_root)
            return JSONResponse(saved)
        except ValueError as error:
            failure = error if isinstance(error, EditorError) else EditorError(str(error))
            return JSONResponse(failure.to_json(), status_code=422)

    return app
