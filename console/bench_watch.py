"""`mavswarm bench run --web`: the console follows the sessions a benchmark run is flying.

Sessions run wherever the backend puts them (this process, worker processes, Ray nodes) and
publish live frames to the driver (`benchmark.running.live_channel`); `LiveBoard` keeps the latest
frame of each, and the console, served from a thread of the driver, shows any of them (with
several workers, the home page lists them to pick one). Watching takes no commands: hands-on
commands would change the run's results.
"""

from __future__ import annotations

import asyncio
import contextlib
import threading
from collections.abc import Iterator
from typing import Any

from benchmark.server.serve import serve_asgi
from console.app import ConsoleState, create_console_app
from console.auth import ConsoleAuth
from console.live import LiveSwarm

__all__ = ["LiveBoard", "serve_in_thread"]


class LiveBoard:
    """The latest frame of every session a run publishes; `update` is the run's `on_live`."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._frames: dict[str, dict[str, Any]] = {}
        self._new: list[LiveSwarm] = []
        self.done: set[str] = set()

    def update(self, payload: dict[str, Any]) -> None:
        ident = str(payload.get("id"))
        with self._lock:
            if "scene" in payload:
                self._new.append(LiveSwarm(ident, str(payload.get("name", ident)),
                                           payload["scene"], frames=lambda: self.frame(ident)))
                self.done.discard(ident)
            if payload.get("done"):
                self.done.add(ident)
            if "frame" in payload:
                self._frames[ident] = {**payload["frame"], "task": payload.get("task", "")}

    def frame(self, ident: str) -> dict[str, Any] | None:
        with self._lock:
            frame = self._frames.get(ident)
            return None if frame is None else {**frame, "done": ident in self.done}

    def refresh(self, state: ConsoleState) -> None:
        """Add the sessions that started since (called on the console's own thread)."""
        with self._lock:
            new, self._new = self._new, []
        for live in new:
            state.lives[live.id] = live


@contextlib.contextmanager
def serve_in_thread(board: LiveBoard, *, host: str, port: int, key: str | None,
                    rate_hz: float) -> Iterator[tuple[str, str]]:
    """The console over `board`, served from a thread while inside; (base URL, key)."""
    auth, key = ConsoleAuth.single_key(key)
    state = ConsoleState(auth, rate_hz=rate_hz)
    state.refresh = lambda: board.refresh(state)
    app = create_console_app(state)
    loop = asyncio.new_event_loop()
    ready: list[str] = []
    started = threading.Event()

    def on_ready(url: str) -> None:
        ready.append(url)
        started.set()

    task_box: list[asyncio.Task[None]] = []
    failure: list[BaseException] = []

    def run() -> None:
        asyncio.set_event_loop(loop)
        task = loop.create_task(serve_asgi(app, host=host, port=port, on_ready=on_ready))
        task_box.append(task)
        try:
            loop.run_until_complete(task)
        except asyncio.CancelledError:
            pass
        except BaseException as error:  # port taken, ...: reported to the caller
            failure.append(error)
            started.set()
        finally:
            loop.run_until_complete(state.aclose())
            loop.close()

    thread = threading.Thread(target=run, name="mavswarm-console", daemon=True)
    thread.start()
    started.wait(30)
    if failure or not ready:
        thread.join(5)
        raise OSError(f"the web console could not start on {host}:{port}: "
                      f"{failure[0] if failure else 'no answer'}")
    try:
        yield ready[0], key
    finally:
        loop.call_soon_threadsafe(task_box[0].cancel)
        thread.join(10)
