"""The live view's command route (operators and admins): hands-on commands for one drone, a
selection or every drone of a live swarm (console.commands).

    GET  /api/live/{id}/commands  {"commands": [...], "refusal": why none runs now, or null}
    POST /api/live/{id}/command   {"drone_id": "d1", "tool": "move_to", "args": {...}}
                                  {"drone_ids": ["d1", "d2"] | "all", "tool": "hold",
                                   "args": {...}, "args_by_drone": {"d2": {...}}}

One drone: the command's result (`status` ok, accepted, rejected, ..., `message`, `command`);
422 for arguments that do not validate. Several: `{"results": {drone: result}}`. The whole
request is checked before anything is sent: the body within every surface's input bounds
(console.request_bodies.CommandBody), an unknown drone is a 404, a bad argument of any drone
a 422, and while a benchmark task runs in the session (benchmark.server.operator_rule)
every command is refused with 409.
"""


import asyncio
from collections.abc import Callable
from typing import TYPE_CHECKING, Annotated, Any

from fastapi import Depends, FastAPI, HTTPException
from fastapi.responses import JSONResponse

from console.commands import COMMANDS
from console.live import LiveSwarm
from console.request_bodies import CommandBody
from llm_tools.body_limit import json_body
from llm_tools.input_limits import preview

if TYPE_CHECKING:
    from console.app import ConsoleState

__all__ = ["add_live_routes"]


def _drones(body: CommandBody, known: list[str]) -> list[str]:
    """The drones a command is for (each once, in the order named)."""
    if body.drone_id is not None:
        chosen = [body.drone_id]
    else:
        chosen = list(known) if body.drone_ids == "all" else list(body.drone_ids or ())
    unknown = [d for d in chosen if d not in known]
    if unknown:
        raise HTTPException(404, f"unknown drone {preview(unknown[0])}; drones: "
                                 f"{', '.join(known[:3])}{' ...' if len(known) > 3 else ''}")
    return list(dict.fromkeys(chosen))


def add_live_routes(app: FastAPI, state: "ConsoleState", staff: Callable[..., str]) -> None:
    """Add the command route to the console's `app` (`staff`: its key dependency)."""
    Staff = Annotated[str, Depends(staff)]

    def live_or_404(live_id: str) -> LiveSwarm:
        lives = state.live_swarms()
        if live_id not in lives:
            raise HTTPException(404, f"no live swarm {preview(live_id)}; live: "
                                     f"{', '.join(lives) or 'none'}")
        return lives[live_id]

    @app.get("/api/live/{live_id}/commands")
    def commands(live_id: str, role: Staff) -> dict[str, Any]:
        """The commands this live view takes, and why none may run now (the page shows it
        and greys its buttons)."""
        commander = live_or_404(live_id).commander
        if commander is None:
            return {"commands": [], "refusal": "this live view takes no commands"}
        return {"commands": list(COMMANDS), "refusal": commander.refusal()}

    @app.post("/api/live/{live_id}/command")
    async def command(live_id: str, role: Staff,
                      body: Annotated[CommandBody, Depends(json_body(CommandBody))]
                      ) -> JSONResponse:
        live = live_or_404(live_id)
        commander = live.commander
        if commander is None:
            raise HTTPException(409, "this live view takes no commands")
        drones = _drones(body, [d["id"] for d in live.scene["drones"]])
        alone = body.drone_id is not None
        per_drone = body.args_by_drone or {}
        stray = [d for d in per_drone if d not in drones]
        if stray:
            raise HTTPException(422, f"args_by_drone names {preview(stray[0])}, which the "
                                     "command is not for")
        args = {d: per_drone.get(d, body.args) for d in drones}
        for drone in drones:  # every drone's arguments, before anything is sent
            _, problem = commander.check(body.tool, args[drone])
            if problem is not None:
                where = "" if alone else f"{drone}: "
                return JSONResponse({"status": "error", "message": where + problem}, 422)
        refusal = commander.refusal()
        if refusal is not None:
            raise HTTPException(409, refusal)
        results = await asyncio.gather(*(commander.start(d, body.tool, args[d] or {})
                                         for d in drones))
        if alone:
            return JSONResponse(results[0])
        return JSONResponse({"results": dict(zip(drones, results, strict=True))})
