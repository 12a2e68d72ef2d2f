"""The hidden checks, for admins only: the current task's tree, and MultiUAV-Plat's
`GET /check/<endpoint>` routes with the reference's query parameters, evaluated on the ground
truth of the current task's window (since the task started, until now)."""

from typing import Annotated, Any

from fastapi import Depends, FastAPI, HTTPException, Query, Request
from starlette.datastructures import QueryParams

from benchmark.scoring.validators import (
    ENDPOINTS,
    CheckContext,
    CheckDefinitionError,
    evaluate,
    parse_tree,
)
from benchmark.scoring.validators.endpoint import Endpoint
from benchmark.server.auth import live_session, require
from benchmark.server.compat.commands import resolve_session
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from llm_tools.input_limits import preview

__all__ = ["add_check_routes", "query_parameters"]


def _context(live: LiveSession) -> CheckContext:
    return CheckContext(live.swarm.recorder, live.session.scenario, live.task_start_s,
                        live.services.clock_s())


def query_parameters(endpoint: Endpoint, query: QueryParams) -> dict[str, Any]:
    """A check's parameters from a query string as the reference's clients send them: a list
    of drones as the parameter repeated (`drone_ids=a&drone_ids=b`), anything else once (its
    last value)."""
    lists = {p.name for p in endpoint.params if p.kind == "drones"}
    return {k: query.getlist(k) if k in lists else query[k] for k in query
            if k != "session"}


def add_check_routes(app: FastAPI, hub: Hub) -> None:
    admin = require(hub, Role.ADMIN)

    @app.get("/check/sessions/{session_id}/task", tags=["checks"],
             summary="Evaluate the current task's hidden checks now (admin)")
    def check_task(session_id: str, caller: Annotated[Caller, Depends(admin)]) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        if live.task.checks is None:
            raise HTTPException(409, f"task {live.task.id!r} has no valid checks: "
                                f"{live.task.error}")
        ctx = _context(live)
        result = evaluate(live.task.checks, ctx)
        return {"task": live.task.id, "window_s": [ctx.t0_s, ctx.t1_s], **result.to_json()}

    @app.get("/check/{endpoint}", tags=["checks"],
             summary="One check endpoint with the reference's query parameters (admin)")
    def check_endpoint(endpoint: str, request: Request, caller: Annotated[Caller, Depends(admin)],
                       session: str | None = Query(None, description="session id")
                       ) -> dict[str, Any]:
        if endpoint not in ENDPOINTS:
            raise HTTPException(404, f"unknown check endpoint {preview(endpoint)}")
        live = resolve_session(hub, caller, session)
        parameters = query_parameters(ENDPOINTS[endpoint], request.query_params)
        try:
            node = parse_tree({"endpoint": endpoint, "parameters": parameters},
                              live.session.scenario, path="query")
        except CheckDefinitionError as error:
            raise HTTPException(422, str(error)) from None
        ctx = _context(live)
        (leaf,) = evaluate(node, ctx).leaves
        return {"result": leaf.result, "value": leaf.to_json()["value"],
                "parameters": leaf.to_json()["parameters"], "error": leaf.error,
                "window_s": [ctx.t0_s, ctx.t1_s]}
