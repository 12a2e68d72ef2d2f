"""The API description per role: each caller sees only the routes its key may use.

`GET /openapi.json` answers with the description for the role of the `X-API-Key` header;
without a key it describes the agent routes, the public contract (so the admin-only check
routes and the operators' views are described only to those roles). `/docs` (Swagger UI)
and `/redoc` render the description without a key.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Annotated, Any

from fastapi import FastAPI, HTTPException, Security
from fastapi.dependencies.models import Dependant
from fastapi.openapi.docs import get_redoc_html, get_swagger_ui_html
from fastapi.openapi.utils import get_openapi
from fastapi.responses import HTMLResponse
from fastapi.routing import APIRoute

from benchmark.server.auth import API_KEY_HEADER, key_header
from benchmark.server.hub import Hub, Role

__all__ = ["add_role_docs", "route_roles"]


def _calls(dependant: Dependant) -> Iterator[Any]:
    for dependency in dependant.dependencies:
        yield dependency.call
        yield from _calls(dependency)


def route_roles(route: APIRoute) -> frozenset[Role]:
    """The roles a route admits (every role when it names none)."""
    for call in _calls(route.dependant):
        roles = getattr(call, "roles", None)
        if roles is not None:
            return frozenset(roles)
    return frozenset(Role)


def add_role_docs(app: FastAPI, hub: Hub) -> None:
    """Serve /openapi.json per role, and /docs and /redoc over it."""
    cache: dict[Role, dict[str, Any]] = {}

    def description(role: Role) -> dict[str, Any]:
        if role not in cache:
            routes = [r for r in app.routes
                      if isinstance(r, APIRoute) and r.include_in_schema
                      and role in route_roles(r)]
            cache[role] = get_openapi(
                title=app.title, version=app.version, routes=routes,
                description=f"{app.description}\n\nThis description lists the routes of the "
                            f"{role.value} role.")
        return cache[role]

    @app.get("/openapi.json", include_in_schema=False)
    def openapi(key: Annotated[str | None, Security(key_header)]) -> dict[str, Any]:
        if not key:
            return description(Role.AGENT)
        caller = hub.caller(key)
        if caller is None:
            raise HTTPException(401, f"unknown API key in the {API_KEY_HEADER} header")
        return description(caller.role)

    @app.get("/docs", include_in_schema=False)
    def swagger() -> HTMLResponse:
        return get_swagger_ui_html(openapi_url="/openapi.json", title=f"{app.title} - docs")

    @app.get("/redoc", include_in_schema=False)
    def redoc() -> HTMLResponse:
        return get_redoc_html(openapi_url="/openapi.json", title=f"{app.title} - ReDoc")
