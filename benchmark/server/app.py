"""The FastAPI application: session, drone, task, tool and perception routes under
`/sessions/{id}`, admin-only check routes under `/check`, and MultiUAV-Plat compatible
`/drones` routes. OpenAPI docs are served at /docs.

An agent's requests run as its thread of control (`agent_threads.py`): the whole session's
agent, or one drone's agent for a drone key, which sees that drone's tools only."""

from typing import Annotated, Any

from fastapi import Depends, FastAPI, HTTPException, Request
from fastapi.responses import JSONResponse

from agent_contract import BudgetExhausted
from benchmark.server.agent_threads import call_tool as call_as_thread
from benchmark.server.agent_threads import read_tool
from benchmark.server.auth import live_session, require
from benchmark.server.checks import add_check_routes
from benchmark.server.compat.collision import add_compat_collision_routes
from benchmark.server.compat.commands import add_compat_routes
from benchmark.server.compat.drones_admin import add_compat_drone_admin_routes
from benchmark.server.compat.environments import add_compat_environment_routes
from benchmark.server.compat.health import add_health_routes
from benchmark.server.compat.histories import add_compat_history_routes
from benchmark.server.compat.lists import add_compat_list_routes
from benchmark.server.compat.request_history import add_compat_request_history
from benchmark.server.compat.screenshot import add_compat_screenshot_routes
from benchmark.server.compat.session_data import add_compat_session_data_routes
from benchmark.server.compat.sessions_admin import add_compat_session_admin_routes
from benchmark.server.compat.tasks import add_compat_task_routes
from benchmark.server.compat.waypoints import add_compat_waypoint_routes
from benchmark.server.compat.world import add_compat_world_routes
from benchmark.server.compat.world_admin import add_compat_world_admin_routes
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from benchmark.server.link_routes import add_link_routes
from benchmark.server.openapi_roles import add_role_docs
from benchmark.server.session_control import add_session_control_routes
from benchmark.server.session_loading import add_session_loading_routes
from benchmark.server.views import session_view, task_view
from llm_tools.body_limit import bound_inputs
from llm_tools.input_limits import InputError, preview
from llm_tools.registry import OUTPUT_SCHEMA, ToolRegistry, served_registry

__all__ = ["create_app", "drone_or_404"]

ANY = (Role.AGENT, Role.OPERATOR, Role.ADMIN)
ACTORS = (Role.AGENT, Role.ADMIN)


def drone_or_404(live: LiveSession, drone: str) -> str:
    """The drone id if the session has it, else HTTP 404 naming the session's drones."""
    if drone not in live.gateway.drones:
        raise HTTPException(404, f"unknown drone {preview(drone)} in session {live.id!r}; "
                            f"drones: {', '.join(live.gateway.drones)}")
    return drone


def _drones(live: LiveSession, caller: Caller) -> dict[str, Any]:
    if caller.role is Role.AGENT:  # the agent's reads are tool calls, counted in its budget
        return read_tool(live.tools, caller.drone_id, "list_drones",
                         lambda tools: tools.list_drones()).to_dict()
    states = live.gateway.list_drones()
    return {"status": "ok", "message": f"{len(states)} drones",
            "drones": [s.to_dict() for s in states]}


async def _body_text(request: Request) -> str:
    """The request body as text for the registry to parse (it answers bad JSON with an error
    a model can read); an empty body is no arguments."""
    try:
        return (await request.body()).decode("utf-8")
    except UnicodeDecodeError as error:
        raise InputError("the body", f"is not UTF-8 text (byte {error.start})") from None


def _add_session_routes(app: FastAPI, hub: Hub, registry: ToolRegistry) -> None:
    anyone, actor = require(hub, *ANY), require(hub, *ACTORS)
    staff = require(hub, Role.OPERATOR, Role.ADMIN)

    @app.get("/sessions", tags=["sessions"], summary="List live sessions (operator, admin)")
    def list_sessions(caller: Annotated[Caller, Depends(staff)]) -> list[dict[str, Any]]:
        return [session_view(live, caller.role) for live in hub.sessions.values()]

    @app.get("/sessions/{session_id}", tags=["sessions"], summary="One session, per role")
    def get_session(session_id: str, caller: Annotated[Caller, Depends(anyone)]) -> dict[str, Any]:
        return session_view(live_session(hub, caller, session_id), caller.role)

    @app.get("/sessions/{session_id}/drones", tags=["drones"], summary="The session's drones")
    def get_drones(session_id: str, caller: Annotated[Caller, Depends(anyone)]) -> dict[str, Any]:
        return _drones(live_session(hub, caller, session_id), caller)

    @app.get("/sessions/{session_id}/drones/{drone_id}", tags=["drones"],
             summary="One drone's state")
    def get_drone(session_id: str, drone_id: str,
                  caller: Annotated[Caller, Depends(anyone)]) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        drone = drone_or_404(live, drone_id)
        if caller.role is Role.AGENT:
            return read_tool(live.tools, caller.drone_id, "drone_state",
                             lambda tools: tools.drone_state(drone)).to_dict()
        return live.gateway.drone_state(drone).to_dict()

    @app.get("/sessions/{session_id}/nearby/{drone_id}", tags=["drones"],
             summary="What a drone's sensor perceives now")
    def get_nearby(session_id: str, drone_id: str,
                   caller: Annotated[Caller, Depends(anyone)]) -> dict[str, Any]:
        live = live_session(hub, caller, session_id)
        drone = drone_or_404(live, drone_id)
        if caller.role is Role.AGENT:
            return read_tool(live.tools, caller.drone_id, "nearby",
                             lambda tools: tools.nearby(drone)).to_dict()
        return live.gateway.nearby(drone).to_dict()

    @app.get("/sessions/{session_id}/task", tags=["tasks"], summary="The current task")
    def get_task(session_id: str, caller: Annotated[Caller, Depends(anyone)]) -> dict[str, Any]:
        return task_view(live_session(hub, caller, session_id), caller.role)

    @app.get("/sessions/{session_id}/tools", tags=["tools"],
             summary="The agent tools with their argument schemas")
    def list_tools(session_id: str, caller: Annotated[Caller, Depends(anyone)]
                   ) -> list[dict[str, Any]]:
        live_session(hub, caller, session_id)
        return [{"name": s.name, "description": s.description, "input_schema": s.input_schema,
                 "output_schema": s.output_schema} for s in registry.specs()]

    @app.post("/sessions/{session_id}/tools/{name}", tags=["tools"],
              summary="Call an agent tool (agent, admin); the body is its arguments object",
              description="Answers 200 with the tool's result, or 422 with an error result "
                          "({status: error, message}) when the arguments are refused. The "
                          "`batch` tool runs several calls side by side, one result each. "
                          "Under the lockstep clock a key's calls run one at a time: a call "
                          "while another of the same thread runs is `rejected`.",
              responses={200: {"description": "The tool's result (`batch`: with `results`)",
                               "content": {"application/json": {"schema": OUTPUT_SCHEMA}}},
                         422: {"description": "The arguments were refused",
                               "content": {"application/json": {"schema": OUTPUT_SCHEMA}}}})
    async def call_tool(session_id: str, name: str, request: Request,
                        caller: Annotated[Caller, Depends(actor)]) -> JSONResponse:
        live = live_session(hub, caller, session_id)
        if registry.get(name) is None:
            raise HTTPException(404, f"unknown tool {preview(name)}; available tools: "
                                f"{', '.join(s.name for s in registry.specs())}")
        body = await _body_text(request)
        result = await call_as_thread(live.tools, caller.drone_id, name,
                                      lambda tools: registry.call(tools, name, body))
        return JSONResponse(result, status_code=422 if result["status"] == "error" else 200)


def create_app(hub: Hub, registry: ToolRegistry | None = None) -> FastAPI:
    """The REST API over `hub`'s live sessions (keys in the X-API-Key header)."""
    registry = registry or served_registry()
    app = FastAPI(title="mavswarm agent API",
                  description="Live benchmark sessions; roles agent, operator and admin by "
                              "API key (X-API-Key header).",
                  openapi_url=None, docs_url=None, redoc_url=None)
    bound_inputs(app)

    @app.exception_handler(BudgetExhausted)
    async def budget_spent(_: Request, error: BudgetExhausted) -> JSONResponse:
        return JSONResponse({"detail": str(error), "reason": error.reason}, status_code=409)

    add_health_routes(app)
    add_compat_world_routes(app, hub, registry)  # first: /sessions/current is not a session id
    add_compat_session_data_routes(app, hub)
    add_session_loading_routes(app, hub)
    _add_session_routes(app, hub, registry)
    add_check_routes(app, hub)
    add_session_control_routes(app, hub)
    add_link_routes(app, hub)
    add_compat_routes(app, hub, registry)
    add_compat_list_routes(app, hub)
    add_compat_collision_routes(app, hub)
    add_compat_history_routes(app, hub)
    add_compat_task_routes(app, hub)
    add_compat_drone_admin_routes(app, hub)
    add_compat_session_admin_routes(app, hub)
    add_compat_screenshot_routes(app, hub)
    add_compat_environment_routes(app, hub)
    add_compat_waypoint_routes(app, hub)
    add_compat_world_admin_routes(app, hub)
    add_compat_request_history(app, hub)
    add_role_docs(app, hub)
    return app
