"""Hands-on commands from the console: an operator picks one drone, a selection or all of
them and tells them to take off, fly to a clicked point, hover, land, return home, or hold
(stop where they are). The arguments are checked against the agent tool of the same name (one
schema for every surface); the commands then go to the MAVLink gateway as a ground station's
would: `hold` interrupts whatever the drone is doing, and a fly-to or a landing replaces the
drone's current goal (as a ground station's Go-to does) instead of being refused as busy.

A command answers once the drone took it: its outcome when it ended within `ACCEPT_WAIT_S`
(a refusal comes at once), otherwise `accepted` while the drone carries it out; how it ends
shows in `activity()` (each drone's command now and its last outcome), which the live frames
carry to the page.

`up --web` has no gateway of its own: the commander opens one (MAVSDK, `udpout` to the swarm's
socket) on the first command, so a swarm nobody commands pays nothing for it. While a benchmark
task runs in a served session, `refusal` (benchmark.server.operator_rule) says why every
command is refused, and nothing is sent.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
from collections.abc import Awaitable, Callable, Mapping
from typing import Any

from llm_tools.input_limits import InputError, check_bounds
from llm_tools.registry import ToolRegistry, default_registry
from llm_tools.schema import validate
from mavlink_gateway import Gateway, Outcome

__all__ = ["ACCEPT_WAIT_S", "COMMANDS", "REPLACING", "Commander"]

COMMANDS = ("take_off", "move_to", "hover", "land", "return_home", "change_altitude", "hold")
REPLACING = frozenset({"move_to", "land"})  # replace the drone's current goal
ACCEPT_WAIT_S = 1.0  # wall seconds a command's answer waits for its outcome before `accepted`

GatewayFactory = Callable[[], Awaitable[Gateway]]
Refusal = Callable[[], str | None]


def _error(message: str) -> dict[str, Any]:
    return {"status": "error", "message": message}


class Commander:
    """Runs hands-on commands on one swarm's drones (see the module docstring)."""

    def __init__(self, session_id: str, gateway: Gateway | GatewayFactory,
                 registry: ToolRegistry | None = None, refusal: Refusal | None = None) -> None:
        self.session_id = session_id
        self._registry = registry or default_registry()
        self._gateway = gateway if isinstance(gateway, Gateway) else None
        self._factory = None if isinstance(gateway, Gateway) else gateway
        self._refusal = refusal
        self._lock = asyncio.Lock()
        self._ids = itertools.count(1)
        self._running: dict[str, dict[int, dict[str, Any]]] = {}  # drone -> id -> command
        self._last: dict[str, dict[str, Any]] = {}
        self._tasks: set[asyncio.Task[dict[str, Any]]] = set()

    def refusal(self) -> str | None:
        """Why no command may run now (a benchmark task is running), or None."""
        return None if self._refusal is None else self._refusal()

    async def _ready(self) -> Gateway:
        async with self._lock:
            if self._gateway is None:
                assert self._factory is not None
                self._gateway = await self._factory()
            return self._gateway

    def check(self, tool: object, args: object) -> tuple[dict[str, Any], str | None]:
        """(the command's arguments, None) or ({}, what is wrong with them)."""
        if not isinstance(tool, str) or tool not in COMMANDS:
            shown = repr(tool)[:40] if isinstance(tool, str) else type(tool).__name__
            return {}, f"{shown} is not a console command; commands: {', '.join(COMMANDS)}"
        if args is None:
            args = {}
        if not isinstance(args, Mapping):
            return {}, f"{tool}: args must be a JSON object"
        try:
            check_bounds(args)
        except InputError as error:
            return {}, f"{tool}: {error}"
        if tool == "hold":
            return ({}, None) if not args else ({}, "hold takes no arguments")
        spec = self._registry.get(tool)
        assert spec is not None and spec.arguments is not None, tool
        values, problems = validate({**args, "drone_id": "-"}, spec.arguments)
        if problems:
            return {}, f"{tool}: " + "; ".join(problems)
        values.pop("drone_id", None)
        return values, None

    async def _call(self, drone_id: str, tool: str, values: dict[str, Any]) -> Outcome:
        gateway = await self._ready()
        if tool == "hold":
            return await gateway.hold(drone_id)
        method = getattr(gateway, tool)
        if tool in REPLACING:
            return await method(drone_id, **values, replace=True)
        return await method(drone_id, **values)

    async def _execute(self, entry: dict[str, Any], values: dict[str, Any]) -> dict[str, Any]:
        drone = entry["drone"]
        try:
            result = (await self._call(drone, entry["name"], values)).to_dict()
        except (TypeError, ValueError) as error:  # a gateway refusing an odd value
            result = _error(f"{entry['name']}: {error}")
        finally:
            running = self._running.get(drone, {})
            running.pop(entry["id"], None)
            if not running:
                self._running.pop(drone, None)
        last = {"id": entry["id"], "name": entry["name"], "status": result["status"],
                "message": result["message"]}
        previous = self._last.get(drone)
        if previous is None or previous["id"] <= entry["id"]:  # a replaced command ends late
            self._last[drone] = last
        return result

    async def start(self, drone_id: str, tool: str, args: Mapping[str, Any],
                    accept_wait_s: float = ACCEPT_WAIT_S) -> dict[str, Any]:
        """Start a command (the caller checked that the drone exists): its outcome if it ended
        within `accept_wait_s`, else `accepted` with the command's id."""
        values, problem = self.check(tool, args)
        if problem is not None:
            return _error(problem)
        await self._ready()  # the first command opens the gateway: not part of the wait
        ident = next(self._ids)
        entry: dict[str, Any] = {"id": ident, "name": tool, "drone": drone_id,
                 "args": {k: round(v, 2) if isinstance(v, float) else v
                          for k, v in values.items()}}
        self._running.setdefault(drone_id, {})[ident] = entry
        task = asyncio.create_task(self._execute(entry, values),
                                   name=f"console-{tool}-{drone_id}")
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        done, _ = await asyncio.wait({task}, timeout=accept_wait_s)
        if done:
            return {**task.result(), "command": entry["id"]}
        return {"status": "accepted", "command": entry["id"],
                "message": f"{tool} accepted by {drone_id}; its outcome shows when it ends"}

    def activity(self) -> dict[str, dict[str, Any]]:
        """Per drone: the command it carries out now (the latest of those still running, or
        None) and how its last one ended."""
        out: dict[str, dict[str, Any]] = {}
        for drone in set(self._running) | set(self._last):
            running = self._running.get(drone) or {}
            out[drone] = {"executing": running[max(running)] if running else None,
                          "last": self._last.get(drone)}
        return out

    async def aclose(self) -> None:
        for task in list(self._tasks):
            task.cancel()
        for task in list(self._tasks):
            with contextlib.suppress(BaseException):
                await task
