"""When an operator's write may act on a served session: never while a benchmark task runs
for the session's agent (it would change that task's result), HTTP 409 naming the task; a
world served without tasks (free flight) takes them. Admins may always fly, as before; the
entity, battery and session writes of the compatibility routes ask this guard for every role.

This is the rule the web console's flight commands, MQTT and link changes follow:
`write_refusal` is `benchmark.server.operator_rule.operator_refusal`."""

from __future__ import annotations

from fastapi import HTTPException

from benchmark.server.hub import Caller, LiveSession, Role
from benchmark.server.operator_rule import operator_refusal

__all__ = ["refuse_flight", "refuse_writes", "write_refusal"]


def write_refusal(live: LiveSession, what: str) -> str | None:
    """Why `what` ("flight commands from an operator key", "drone creation", ...) may not act
    on `live` now, or None when it may."""
    return operator_refusal(live, what)


def refuse_writes(live: LiveSession, what: str) -> None:
    """HTTP 409 when `write_refusal` refuses `what`."""
    reason = write_refusal(live, what)
    if reason is not None:
        raise HTTPException(409, reason)


def refuse_flight(live: LiveSession, caller: Caller) -> None:
    """An operator (the reference's SYSTEM role) flies drones only outside a benchmark task;
    agents and admins fly as before."""
    if caller.role is Role.OPERATOR:
        refuse_writes(live, "flight commands from an operator key")
