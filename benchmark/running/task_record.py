"""One task's record in results.jsonl, as `benchmark.running.episode` writes it: its key, the fields
that name the task, the verdict, the checks and the costs.

`TaskRecord` is the record's type; `record_problem` says in one line what is wrong with a
record read back (None: nothing), so that resume and reports never take a damaged line for a
task: the key must be the one its fields make (`record_key`), and, where the sessions of a run
are known, name one of their tasks.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, StrictBool, StrictInt, ValidationError

__all__ = ["KnownTasks", "TaskRecord", "record_key", "record_problem"]

KnownTasks = Mapping[str, frozenset[str]]
"""Session id -> the ids of its tasks: what a run may have recorded."""

_Name = Annotated[str, Field(min_length=1)]
_Count = Annotated[StrictInt, Field(ge=0)]
_Seconds = Annotated[float, Field(ge=0.0, allow_inf_nan=False)]


def record_key(session_id: str, task_id: str, agent: str, trial: int) -> str:
    """The key of one task's record: session, task, agent and trial."""
    return f"{session_id}/{task_id}/{agent}/{trial}"


class Tokens(BaseModel):
    """An LLM agent's token use on the task, and its price."""

    model_config = ConfigDict(extra="forbid")
    prompt: _Count
    completion: _Count
    cost_usd: _Seconds  # a non-negative finite amount


class TaskRecord(BaseModel):
    """A results.jsonl record. Fields added later are kept (extra="allow"); the ones below
    must be there, of their type."""

    model_config = ConfigDict(extra="allow")

    key: _Name
    session: _Name
    family: str
    level: str
    task: _Name
    template: str
    category: str
    agent: _Name
    trial: _Count
    passed: StrictBool
    checks: list[dict[str, Any]]
    checks_total: _Count
    checks_passed: _Count
    finish: _Name
    error: str | None
    tool_calls: _Count
    sim_time_s: _Seconds
    wall_time_s: _Seconds
    tokens: Tokens | None
    overhead_s: dict[str, _Seconds] = {}  # absent in records written before it existed
    clock: str | None = None
    end_state: dict[str, Any] | None = None
    window_s: list[float] | None = None


def _first_error(error: ValidationError) -> str:
    problems = error.errors(include_url=False)
    first = problems[0]
    where = ".".join(str(part) for part in first["loc"]) or "the record"
    more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
    return f"field {where!r}: {first['msg']}{more}"


def record_problem(value: Mapping[str, Any], known: KnownTasks | None = None) -> str | None:
    """What makes `value` no task record (of the tasks `known`), in one line; None if it is
    one."""
    try:
        record = TaskRecord.model_validate(value)
    except ValidationError as error:
        return f"not a task record: {_first_error(error)}"
    expected = record_key(record.session, record.task, record.agent, record.trial)
    if record.key != expected:
        return (f"record key {record.key!r} does not match its fields (session, task, agent, "
                f"trial make {expected!r})")
    if record.checks_passed > record.checks_total:
        return (f"record {record.key!r} has {record.checks_passed} checks passed of "
                f"{record.checks_total}")
    if known is not None:
        if record.session not in known:
            return (f"record {record.key!r} names session {record.session!r}, which is not "
                    f"one of this run's sessions ({', '.join(sorted(known)) or 'none'}); "
                    "results of other sessions belong in another folder (--out)")
        if record.task not in known[record.session]:
            return (f"record {record.key!r} names task {record.task!r}, which session "
                    f"{record.session!r} does not have")
    return None
