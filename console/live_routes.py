"""The live view's command route (operators and admins): hands-on commands for one drone, a
selection or every drone of a live swarm (console.commands).

    POST /api/live/{id}/command   {"drone_id": "d1", "tool": "move_to", "args": {...}}
                                  {"drone_ids": ["d1", "d2"] | "all", "tool": "hold",
                                   "args": {...}, "args_by_drone": {"d2": {...}}}

One drone: the command's result (`status` ok, accepted, rejected, ..., `message`, `command`);
422 for arguments that do not validate. Several: `{"results": {drone: result}}`. The whole
request is checked before anything is sent: an unknown drone is a 404, a bad argument of any
drone a 422, and while a benchmark task runs in the session (benchmark.server.operator_rule)
every command is refused with 409.
"""


import asyncio
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Annotated, Any

from fastapi import Depends, FastAPI, HTTPException, Request
from fastapi.responses import JSONResponse

from llm_tools.input_limits import InputError, parse_json, preview

if TYPE_CHECKING:
    from console.app import ConsoleState

__all__ = ["add_live_routes"]


async def _body(request: Request) -> dict[str, Any]:
    raw = await request.body()
    try:
        body = parse_json(raw or b"{}", "the body")
    except InputError as error:
        raise HTTPException(error.http_status, str(error)) from None
    if not isinstance(body, dict) or not isinstance(body.get("tool"), str):
        raise HTTPException(422, "send {drone_id: str, tool: str, args: {...}} or "
                                 "{drone_ids: [str] | \"all\", tool: str, args: {...}}")
    return body


def _drones(body: Mapping[str, Any], known: list[str]) -> tuple[list[str], bool]:
    """The drones a command is for, and whether one was named alone (`drone_id`)."""
    if "drone_id" in body:
        if "drone_ids" in body:
            raise HTTPException(422, "send drone_id or drone_ids, not both")
        chosen: Any = [body["drone_id"]]
    else:
        chosen = body.get("drone_ids")
        if chosen == "all":
            chosen = list(known)
    if not isinstance(chosen, list) or not chosen \
            or not all(isinstance(d, str) for d in chosen):
        raise HTTPException(422, "drone_id must be a drone's id, drone_ids a non-empty list "
                                 "of ids or \"all\"")
    unknown = [d for d in chosen if d not in known]
    if unknown:
        raise HTTPException(404, f"unknown drone {preview(unknown[0])}; drones: "
                                 f"{', '.join(known[:3])}{' ...' if len(known) > 3 else ''}")
    return list(dict.fromkeys(chosen)), "drone_id" in body


def add_live_routes(app: FastAPI, state: "ConsoleState", staff: Callable[..., str]) -> None:
    """Add the command route to the console's `app` (`staff`: its key dependency)."""
    Staff = Annotated[str, Depends(staff)]

    @app.post("/api/live/{live_id}/command")
    async def command(live_id: str, request: Request, role: Staff) -> JSONResponse:
        lives = state.live_swarms()
        if live_id not in lives:
            raise HTTPException(404, f"no live swarm {preview(live_id)}; live: "
                                     f"{', '.join(lives) or 'none'}")
        live = lives[live_id]
        commander = live.commander
        if commander is None:
            raise HTTPException(409, "this live view takes no commands")
        body = await _body(request)
        drones, alone = _drones(body, [d["id"] for d in live.scene["drones"]])
        per_drone = body.get("args_by_drone") or {}
        if not isinstance(per_drone, dict):
            raise HTTPException(422, "args_by_drone must map drone ids to args objects")
        stray = [d for d in per_drone if d not in drones]
        if stray:
            raise HTTPException(422, f"args_by_drone names {preview(stray[0])}, which the "
                                     "command is not for")
        args = {d: per_drone.get(d, body.get("args")) for d in drones}
        for drone in drones:  # every drone's arguments, before anything is sent
            _, problem = commander.check(body["tool"], args[drone])
            if problem is not None:
                where = "" if alone else f"{drone}: "
                return JSONResponse({"status": "error", "message": where + problem}, 422)
        refusal = commander.refusal()
        if refusal is not None:
            raise HTTPException(409, refusal)
        results = await asyncio.gather(*(commander.start(d, body["tool"], args[d] or {})
                                         for d in drones))
        if alone:
            return JSONResponse(results[0])
        return JSONResponse({"results": dict(zip(drones, results, strict=True))})
