"""MultiUAV-Plat's session histories (entities.md section 6.4) for the current task's window,
read from the agent's tool log and the emulator's ground truth:

- `command_history`: every flight command the agent ran (through any surface), as
  `{command_id, drone_id, command, parameters, status, message, timestamp}`;
- `status_history`: per drone, its status, position and battery at the end of each of its
  commands, kept when one of them changed (position by more than 1 cm, battery by more than
  0.1 points), the last 100;
- `path_history`: per drone, the start and end points of its move commands (move_to,
  move_towards, move_along_path), as the reference appends them.

Times are simulated seconds. Routes: `GET /drones/{id}/commands`, `GET /commands/{id}` (every
role; an agent reads its own session) and, for operators and admins,
`GET /sessions/{id}/command-history`, `status-history`, `path-history`, `target-reaches`,
`moving-target-tracking` and `area-coverage`."""

from collections.abc import Mapping
from typing import Annotated, Any

import numpy as np
from fastapi import Depends, FastAPI, HTTPException, Query

from benchmark.scoring.validators import CheckContext
from benchmark.server.auth import live_session, require
from benchmark.server.compat.commands import COMMANDS, command_id, resolve_session
from benchmark.server.compat.statistics import check_context, reach_history
from benchmark.server.compat.tracking import moving_target_tracking
from benchmark.server.hub import Caller, Hub, LiveSession, Role
from llm_tools.input_limits import preview

__all__ = ["add_compat_history_routes", "command_history", "path_history",
           "session_histories", "status_history"]

_COMMAND_TOOLS = frozenset(c.tool for c in COMMANDS.values())
_MOVES = frozenset({"move_to", "move_towards", "move_along_path"})
_STATUS = {"ok": "success", "partial": "partial_success"}
STATUS_KEPT = 100
_GROUND_M = 0.3


def _calls(live: LiveSession) -> list[dict[str, Any]]:
    raw = live.tools.__dict__.get("calls", [])
    return [c for c in raw if c["name"] in _COMMAND_TOOLS and c["drone"] is not None
            and c["t0_s"] >= live.task_start_s - 1e-6]  # since the window began (a reset)


def command_history(live: LiveSession) -> list[dict[str, Any]]:
    """The reference's `command_history`: the agent's flight commands in the order they
    began."""
    return [{"command_id": command_id(live, c["i"]), "drone_id": str(c["drone"]),
             "command": c["name"],
             "parameters": {k: v for k, v in c["args"].items() if k != "drone_id"},
             "status": _STATUS.get(str(c["status"]), "error" if c["status"] else "running"),
             "message": c["message"], "timestamp": c["t0_s"]}
            for c in sorted(_calls(live), key=lambda c: (c["t0_s"], c["i"]))]


def _sample(ctx: CheckContext, drone: str, t_s: float) -> tuple[list[float], float] | None:
    """(x, y, z) and battery of the drone's truth at `t_s` (the last sample at or before it)."""
    try:
        track = ctx.window(drone)
    except Exception:
        return None
    if track.empty:
        return None
    k = max(0, int(np.searchsorted(track.t_s, t_s, side="right")) - 1)
    x, y, z = (round(float(v), 2) for v in track.xyz_m[k])
    return [x, y, z], round(float(track.battery_pct[k]), 2)


def status_history(live: LiveSession) -> dict[str, list[dict[str, Any]]]:
    """Per drone, its state after each of its commands, kept when it changed."""
    ctx = check_context(live)
    out: dict[str, list[dict[str, Any]]] = {}
    for call in sorted(_calls(live), key=lambda c: (c["t0_s"], c["i"])):
        if call["t1_s"] is None:
            continue
        drone = str(call["drone"])
        sample = _sample(ctx, drone, call["t1_s"])
        if sample is None:
            continue
        (x, y, z), battery = sample
        status = "hovering" if z > _GROUND_M else "idle"
        entries = out.setdefault(drone, [])
        if entries:
            last = entries[-1]
            moved = max(abs(a - b) for a, b in zip((x, y, z), last["_xyz"], strict=True))
            if (last["status"] == status and moved <= 0.01
                    and abs(last["battery_level"] - battery) <= 0.1):
                continue
        entries.append({"status": status, "position": {"x": x, "y": y, "z": z},
                        "battery_level": battery, "timestamp": call["t1_s"], "_xyz": (x, y, z)})
    return {drone: [{k: v for k, v in e.items() if k != "_xyz"} for e in entries[-STATUS_KEPT:]]
            for drone, entries in out.items()}


def path_history(live: LiveSession) -> dict[str, list[dict[str, float]]]:
    """Per drone, the start point of each move (when not where the last one ended) and its
    end point."""
    ctx = check_context(live)
    out: dict[str, list[dict[str, float]]] = {}
    for call in sorted(_calls(live), key=lambda c: (c["t0_s"], c["i"])):
        if call["name"] not in _MOVES or call["t1_s"] is None:
            continue
        drone = str(call["drone"])
        points = out.setdefault(drone, [])
        for t_s in (call["t0_s"], call["t1_s"]):
            sample = _sample(ctx, drone, t_s)
            if sample is None:
                continue
            point = dict(zip("xyz", sample[0], strict=True))
            if not points or points[-1] != point:
                points.append(point)
    return out


def session_histories(live: LiveSession) -> dict[str, Any]:
    """The command, status and path histories of session data's `history` block."""
    return {"command_history": command_history(live),
            "status_history": _with_volume(live, status_history(live)),
            "path_history": path_history(live)}


def _with_volume(live: LiveSession, history: Mapping[str, list[dict[str, Any]]]
                 ) -> dict[str, list[dict[str, Any]]]:
    capacity = {r.get("id"): r.get("battery_capacity")
                for r in live.session.data.get("drones", []) if isinstance(r, Mapping)}
    out = {}
    for drone, entries in history.items():
        cap = capacity.get(drone)
        mah = float(cap) if isinstance(cap, int | float) and not isinstance(cap, bool) else None
        out[drone] = [{**e, "battery_volume": None if mah is None
                       else round(e["battery_level"] / 100.0 * mah, 2)} for e in entries]
    return out


def add_compat_history_routes(app: FastAPI, hub: Hub) -> None:
    anyone = require(hub, Role.AGENT, Role.OPERATOR, Role.ADMIN)
    staff = require(hub, Role.OPERATOR, Role.ADMIN)
    pick = Query(None, description="session id (operator and admin keys)")

    @app.get("/drones/{drone_id}/commands", tags=["multiuav-plat"],
             summary="A drone's command history in the current task")
    def drone_commands(drone_id: str, caller: Annotated[Caller, Depends(anyone)],
                       session: str | None = pick) -> list[dict[str, Any]]:
        live = resolve_session(hub, caller, session)
        if drone_id not in live.gateway.drones:
            raise HTTPException(404, f"unknown drone {preview(drone_id)} in session "
                                f"{live.id!r}")
        return [c for c in command_history(live) if c["drone_id"] == drone_id]

    @app.get("/commands/{command}", tags=["multiuav-plat"], summary="One command by id")
    def one_command(command: str, caller: Annotated[Caller, Depends(anyone)],
                    session: str | None = pick) -> dict[str, Any]:
        live = resolve_session(hub, caller, session)
        found = next((c for c in command_history(live) if c["command_id"] == command), None)
        if found is None:
            raise HTTPException(404, f"unknown command {preview(command)} in session "
                                f"{live.id!r}")
        return found

    def history(session_id: str, caller: Caller) -> LiveSession:
        return live_session(hub, caller, session_id)

    @app.get("/sessions/{session_id}/command-history", tags=["multiuav-plat"],
             summary="The session's command history (operator, admin)")
    def commands_of(session_id: str, caller: Annotated[Caller, Depends(staff)]
                    ) -> list[dict[str, Any]]:
        return command_history(history(session_id, caller))

    @app.get("/sessions/{session_id}/status-history", tags=["multiuav-plat"],
             summary="Each drone's status history (operator, admin)")
    def statuses_of(session_id: str, caller: Annotated[Caller, Depends(staff)]
                    ) -> dict[str, Any]:
        live = history(session_id, caller)
        return _with_volume(live, status_history(live))

    @app.get("/sessions/{session_id}/path-history", tags=["multiuav-plat"],
             summary="Each drone's path history (operator, admin)")
    def paths_of(session_id: str, caller: Annotated[Caller, Depends(staff)]
                 ) -> dict[str, Any]:
        return path_history(history(session_id, caller))

    @app.get("/sessions/{session_id}/target-reaches", tags=["multiuav-plat"],
             summary="Target reaches by drone and by target (operator, admin)")
    def reaches_of(session_id: str, caller: Annotated[Caller, Depends(staff)]
                   ) -> dict[str, Any]:
        return dict(reach_history(history(session_id, caller))["target_reaches"])

    @app.get("/sessions/{session_id}/moving-target-tracking", tags=["multiuav-plat"],
             summary="Moving-target tracking (operator, admin)")
    def tracking_of(session_id: str, caller: Annotated[Caller, Depends(staff)]
                    ) -> dict[str, Any]:
        return dict(moving_target_tracking(check_context(history(session_id, caller))))

    @app.get("/sessions/{session_id}/area-coverage", tags=["multiuav-plat"],
             summary="Area coverage by target (operator, admin)")
    def coverage_of(session_id: str, caller: Annotated[Caller, Depends(staff)]
                    ) -> dict[str, Any]:
        return dict(reach_history(history(session_id, caller))["area_coverage"])
