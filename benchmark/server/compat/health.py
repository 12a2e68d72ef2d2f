"""Liveness routes that need no key and say nothing about the world: MultiUAV-Plat's `GET /`
and `GET /version`, and `GET /health` (the reference agent service's name for it)."""

from importlib.metadata import PackageNotFoundError, version
from typing import Any

from fastapi import FastAPI

__all__ = ["NAME", "add_health_routes", "server_version"]

NAME = "mavswarm REST API"


def server_version() -> str:
    """The installed mavswarm version ("unknown" when it is not installed)."""
    try:
        return version("mavswarm")
    except PackageNotFoundError:
        return "unknown"


def add_health_routes(app: FastAPI) -> None:
    online = {"status": "online", "message": f"{NAME} is running"}

    @app.get("/", tags=["health"], summary="Server status (no key needed)")
    def root() -> dict[str, Any]:
        return dict(online)

    @app.get("/health", tags=["health"], summary="Server status (no key needed)")
    def health() -> dict[str, Any]:
        return dict(online)

    @app.get("/version", tags=["health"], summary="Server name and version (no key needed)")
    def server() -> dict[str, Any]:
        return {"name": NAME, "version": server_version()}
