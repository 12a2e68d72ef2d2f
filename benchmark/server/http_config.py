"""How every HTTP server of mavswarm (`mavswarm serve`, a hosted run's endpoint and its
sessions' servers) runs under uvicorn.

An idle keep-alive connection is closed by the server after `KEEP_ALIVE_S`. That is longer
than the idle expiry of the usual HTTP clients (httpx and aiohttp drop a connection idle 5 s or
15 s), so the client closes first: were the server the one to close, a client reusing the
connection at that moment (an agent that thought for about as long as the timeout) would have
its request reset on the wire instead of answered.
"""

from __future__ import annotations

from typing import Any

import uvicorn

__all__ = ["KEEP_ALIVE_S", "uvicorn_config"]

KEEP_ALIVE_S = 75
"""Seconds an idle connection is kept open by the server."""


def uvicorn_config(app: Any, **options: Any) -> uvicorn.Config:
    """uvicorn's config for `app`: warnings only, the keep-alive above, then `options`."""
    return uvicorn.Config(app, **{"log_level": "warning", "timeout_keep_alive": KEEP_ALIVE_S,
                                  **options})
