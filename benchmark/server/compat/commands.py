"""MultiUAV-Plat compatible agent routes: `GET /drones`, `GET /drones/{id}` and the direct
commands `POST /drones/{id}/command/{name}` (scalar parameters as query parameters,
`move_along_path` waypoints as a JSON body), answered in the reference command-response
shape. An agent key acts on its own session; other roles name one with `?session=`."""

import hashlib
import math
import secrets
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Annotated, Any

from fastapi import Depends, FastAPI, HTTPException, Query, Request

from benchmark.server.auth import live_session, require
from benchmark.server.compat.entities import compat_drone, compat_nearby
from benchmark.server.compat.write_guard import refuse_flight
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from llm_tools.input_limits import InputError, check_text, parse_json, parse_number, preview
from llm_tools.registry import ToolRegistry
from mavlink_gateway import DroneState, Status

__all__ = ["COMMANDS", "UNSUPPORTED", "Command", "add_compat_routes", "command_id",
           "resolve_session", "run_command"]

_STATUS = {Status.OK.value: "success", Status.PARTIAL.value: "partial_success"}
_REQUIRED = object()


def _num(params: Mapping[str, Any], key: str, default: Any = _REQUIRED) -> float:
    if key not in params or params[key] in (None, ""):
        if default is _REQUIRED:
            raise HTTPException(422, f"parameter {key!r} is required")
        return float(default)
    return parse_number(params[key], f"parameter {key!r}")


def _text(params: Mapping[str, Any], key: str) -> str:
    value = params.get(key)
    if not isinstance(value, str) or not value:
        raise HTTPException(422, f"parameter {key!r} is required (a non-empty string)")
    check_text(value, f"parameter {key!r}")
    return value


def _heading(p: Mapping[str, Any]) -> float:
    if p.get("heading") not in (None, ""):
        return _num(p, "heading")
    if p.get("dx") not in (None, "") and p.get("dy") not in (None, ""):
        dx, dy = _num(p, "dx"), _num(p, "dy")
        if dx == 0.0 and dy == 0.0:
            raise HTTPException(400, "dx and dy are both 0: no direction to move in")
        return math.degrees(math.atan2(dx, dy)) % 360.0
    if p.get("azimuth") not in (None, ""):
        return _num(p, "azimuth")
    raise HTTPException(400, "Direction must be specified using 'heading', 'dx/dy', or "
                        "'azimuth'")


def _waypoints(body: Any, state: DroneState) -> list[list[float]]:
    raw = body.get("waypoints") if isinstance(body, Mapping) else body
    if not isinstance(raw, list) or not raw:
        raise HTTPException(422, "waypoints: expected a non-empty list of {x, y[, z]}")
    points = []
    for k, point in enumerate(raw):
        if isinstance(point, Mapping) and isinstance(point.get("coordinates"), Mapping):
            point = point["coordinates"]
        if not isinstance(point, Mapping):
            raise HTTPException(422, f"waypoints[{k}]: expected an object {{x, y[, z]}}, "
                                f"got {preview(point)}")
        try:
            points.append([_num(point, "x"), _num(point, "y"),
                           _num(point, "z", state.altitude_m)])
        except InputError as error:
            raise InputError(f"waypoints[{k}]: {error.where}", error.problem) from None
    return points


ToolArguments = Callable[[Mapping[str, Any], Any, DroneState], dict[str, Any]]


def _none(params: Mapping[str, Any], body: Any, state: DroneState) -> dict[str, Any]:
    return {}


@dataclass(frozen=True)
class Command:
    """A MultiUAV-Plat command: the agent tool it runs, and how the reference's parameters
    (query strings, a JSON body, defaults from the drone's state) become that tool's typed
    arguments. The tool itself, with its validation and budget, is the one definition in
    `agent_contract.AgentTools`."""

    tool: str
    arguments: ToolArguments = _none


COMMANDS: dict[str, Command] = {
    "take_off": Command("take_off", lambda p, b, s: {"altitude_m": _num(p, "altitude", 10.0)}),
    "land": Command("land"),
    "move_to": Command("move_to", lambda p, b, s: {
        "x": _num(p, "x", s.x_m), "y": _num(p, "y", s.y_m), "z": _num(p, "z", s.altitude_m)}),
    "move_towards": Command("move_towards", lambda p, b, s: {
        "heading_deg": _heading(p), "distance_m": _num(p, "distance"),
        "dz_m": _num(p, "dz", 0.0)}),
    "move_along_path": Command("move_along_path",
                               lambda p, b, s: {"waypoints": _waypoints(b, s)}),
    "change_altitude": Command("change_altitude",
                               lambda p, b, s: {"altitude_m": _num(p, "altitude")}),
    "hover": Command("hover", lambda p, b, s: {"duration_s": _num(p, "duration", 1.0)}),
    "rotate": Command("rotate", lambda p, b, s: {"heading_deg": _num(p, "heading")}),
    "return_home": Command("return_home"),
    "set_home": Command("set_home"),
    "take_photo": Command("take_photo"),
    "charge": Command("charge"),
    "send_message": Command("send_message", lambda p, b, s: {
        "to_drone_id": _text(p, "target_drone_id"), "text": _text(p, "message")}),
    "broadcast": Command("broadcast", lambda p, b, s: {"text": _text(p, "message")}),
}


UNSUPPORTED: dict[str, str] = {
    "calibrate": "the emulated autopilots have no sensors to calibrate: a drone on the ground "
                 "is ready to take off as it is",
    "connect": "every drone is connected over MAVLink from the start",
    "disconnect": "a drone cannot be taken off its MAVLink link here",
    "emergency": "an emergency stop would drop the drone where it is; use land or "
                 "return_home",
}
"""MultiUAV-Plat commands that do not apply to flight over MAVLink, with the reason. They are
answered like a refused command (HTTP 200, status "error") and change nothing."""


def command_id(live: LiveSession, index: int) -> str:
    """The 8-hex id of the agent's tool call `index` (its place in the tool log) in the
    session's current task: the same on every read (`GET /commands/{id}`)."""
    return hashlib.sha256(f"{live.id}/{live.task.id}/{index}".encode()).hexdigest()[:8]


def _logged_id(live: LiveSession, since: int, tool: str, drone_id: str) -> str:
    """The id of the call of `tool` on `drone_id` logged since position `since`."""
    calls = live.tools.__dict__.get("calls", [])
    found = next((c["i"] for c in calls[since:] if c["name"] == tool
                  and c["drone"] == drone_id), None)
    return secrets.token_hex(4) if found is None else command_id(live, found)


def resolve_session(hub: Hub, caller: Caller, session: str | None) -> LiveSession:
    """The caller's session: an agent's own, else the one named (or the current one)."""
    if caller.role is Role.AGENT:
        assert caller.session_id is not None
        return live_session(hub, caller, session or caller.session_id)
    if session is None:
        session = hub.current()
        if session is None:
            raise HTTPException(400, "several sessions are live and none is current: name one "
                                f"with ?session=<id> ({', '.join(hub.sessions)})")
    return live_session(hub, caller, session)


def _state(live: LiveSession, drone: str) -> DroneState:
    outcome = live.gateway.drone_state(drone)
    if outcome.state is None:
        raise HTTPException(404, f"unknown drone {preview(drone)} in session {live.id!r}; "
                            f"drones: {', '.join(live.gateway.drones)}")
    return outcome.state


async def run_command(live: LiveSession, registry: ToolRegistry, drone_id: str, name: str,
                      params: Mapping[str, Any], body: Any) -> dict[str, Any]:
    """Run a MultiUAV-Plat command through its agent tool; the answer in the reference's
    shape."""
    command = COMMANDS.get(name)
    if command is None and name not in UNSUPPORTED:
        raise HTTPException(404, f"unknown command {preview(name)}; commands: "
                            f"{', '.join(COMMANDS)}")
    state = _state(live, drone_id)
    if command is None:
        return {"command_id": secrets.token_hex(4), "drone_id": drone_id, "command": name,
                "status": "error", "message": f"{name} is not supported: {UNSUPPORTED[name]}; "
                "nothing was done", "timestamp": time.time()}
    arguments = {"drone_id": drone_id, **command.arguments(dict(params), body, state)}
    since = len(live.tools.__dict__.get("calls", []))
    result = await registry.call(live.tools, command.tool, arguments)
    status = _STATUS.get(result["status"], "error")
    answer = {"command_id": _logged_id(live, since, command.tool, drone_id),
              "drone_id": drone_id, "command": name, "status": status,
              "message": result["message"], "timestamp": time.time()}
    if name == "move_along_path":
        answer.update(_path_points(arguments["waypoints"], status, result.get("reached", 0)))
    return answer


def _path_points(points: list[list[float]], status: str, reached: int) -> dict[str, Any]:
    """move_along_path's extra fields: the waypoints reached and not reached (all null on
    error, as the reference gives them)."""
    if status == "error":
        return dict.fromkeys(("successful_points_count", "successful_points",
                              "unsuccessful_points_count", "unsuccessful_points"))
    done = len(points) if status == "success" else int(reached)
    return {"successful_points_count": done, "successful_points": points[:done],
            "unsuccessful_points_count": len(points) - done,
            "unsuccessful_points": points[done:]}


def add_compat_routes(app: FastAPI, hub: Hub, registry: ToolRegistry) -> None:
    """Add the MultiUAV-Plat compatible /drones routes to `app`."""
    anyone = require(hub, Role.AGENT, Role.OPERATOR, Role.ADMIN)
    actor = require(hub, Role.AGENT, Role.OPERATOR, Role.ADMIN)
    pick = Query(None, description="session id (operator and admin keys)")

    @app.get("/drones", tags=["multiuav-plat"], summary="The session's drones")
    def drones(caller: Annotated[Caller, Depends(anyone)], session: str | None = pick
               ) -> list[dict[str, Any]]:
        live = resolve_session(hub, caller, session)
        return [compat_drone(live, s) for s in live.gateway.list_drones()]

    @app.get("/drones/{drone_id}", tags=["multiuav-plat"], summary="One drone")
    def drone(drone_id: str, caller: Annotated[Caller, Depends(anyone)],
              session: str | None = pick) -> dict[str, Any]:
        live = resolve_session(hub, caller, session)
        return compat_drone(live, _state(live, drone_id))

    @app.post("/drones/{drone_id}/command/{name}", tags=["multiuav-plat"],
              summary="A direct command; scalar parameters as query parameters")
    async def command(drone_id: str, name: str, request: Request,
                      caller: Annotated[Caller, Depends(actor)], session: str | None = pick
                      ) -> dict[str, Any]:
        raw = (await request.body()).strip()
        try:
            body = parse_json(raw) if raw else None
        except InputError as error:
            raise InputError(f"{preview(name)}: {error.where}", error.problem,
                             http_status=error.http_status) from None
        live = resolve_session(hub, caller, session)
        refuse_flight(live, caller)
        return await run_command(live, registry, drone_id, name, dict(request.query_params),
                                 body)

    def _nearby(live: LiveSession, caller: Caller, drone_id: str) -> dict[str, Any]:
        _state(live, drone_id)
        source = live.tools if caller.role is Role.AGENT else live.gateway
        return compat_nearby(live, source.nearby(drone_id).data or {})

    @app.get("/drones/{drone_id}/nearby", tags=["multiuav-plat"],
             summary="What the drone senses: {drones, targets, obstacles}")
    def nearby(drone_id: str, caller: Annotated[Caller, Depends(anyone)],
               session: str | None = pick) -> dict[str, Any]:
        return _nearby(resolve_session(hub, caller, session), caller, drone_id)

    @app.get("/drones/{drone_id}/nearby/{kind}", tags=["multiuav-plat"],
             summary="One kind of what the drone senses: drones, targets or obstacles")
    def nearby_kind(drone_id: str, kind: str, caller: Annotated[Caller, Depends(anyone)],
                    session: str | None = pick) -> list[dict[str, Any]]:
        if kind not in ("drones", "targets", "obstacles"):
            raise HTTPException(404, f"unknown kind {preview(kind)}; use drones, targets or "
                                "obstacles")
        return _nearby(resolve_session(hub, caller, session), caller, drone_id)[kind]

    @app.get("/sessions/current/tasks/next", tags=["multiuav-plat"],
             summary="The task to do now (its text only)")
    def next_task(caller: Annotated[Caller, Depends(anyone)], session: str | None = pick
                  ) -> dict[str, Any]:
        live = resolve_session(hub, caller, session)
        return {"id": live.task.id, "content": live.task.text}
