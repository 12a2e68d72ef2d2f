"""mavswarm benchmark session files (schema ``mavswarm.session/1``).

A session file is one JSON object:

- ``schema``: ``"mavswarm.session/1"``; ``id``, ``name``, ``description``;
  ``family``, ``level``, ``index``, ``seed`` (generated sessions; an imported one has
  ``family`` = its task type, ``level`` = ``"imported"``, ``index`` 0, ``seed`` null);
  ``task_type``; ``map_size_m`` [width, height]; ``safety_margin_m``; ``origin``
  (latitude_deg, longitude_deg, altitude_amsl_m of x = y = 0); ``environment`` (weather,
  temperature, humidity, wind_speed m/s, wind_direction: fixed for the whole session).
- ``drones``, ``targets``, ``obstacles``: entity objects with the MultiUAV-Plat entity fields
  (positions ``{x, y, z}`` in local ENU metres; see ``emulator.scenario``).
- ``tasks``: ordered list of task objects: ``id``, ``template``, ``category``, ``difficulty``,
  ``text`` (what the agent is told), ``aliases`` (other phrasings), ``budget``
  ({tool_calls, sim_time_s}), and two hidden parts, ``checks`` (the check tree) and
  ``oracle`` (the reference plan, or null); optionally a third, ``faults``
  (benchmark.authoring.task_faults).
- ``link_faults`` (optional): the session's link faults (emulator.link_faults).

The format's models and JSON Schema are in `benchmark.authoring.session_model`
(`session.schema.json`).
Loading never lets one bad task stop the others: a task whose fields or check tree are invalid
is kept with its `error` set, and is recorded as a task error when run.
"""

from __future__ import annotations

import functools
import hashlib
import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from agent_contract.protocol import TaskBudget
from benchmark.authoring.plan_steps import parse_plan
from benchmark.authoring.session_model import SCHEMA, SessionHeader, TaskFile
from benchmark.authoring.task_faults import TaskFaults, task_faults
from benchmark.scoring.validators import CheckDefinitionError, Node, parse_tree
from emulator.scenario import Scenario, ScenarioError, scenario_from_model
from emulator.scenario_errors import describe_error

__all__ = [
    "FINGERPRINT_CHARS",
    "SCHEMA",
    "Session",
    "SessionFileError",
    "TaskSpec",
    "dump_session",
    "load_session",
    "read_session_json",
    "session_from_dict",
    "task_from_dict",
    "text_fingerprint",
]

FINGERPRINT_CHARS = 16


def text_fingerprint(text: str | bytes) -> str:
    """The first FINGERPRINT_CHARS hex digits of the sha256 of a text (a session file's
    canonical text: its fingerprint, see benchmark.authoring.fingerprint)."""
    data = text.encode("utf-8") if isinstance(text, str) else text
    return hashlib.sha256(data).hexdigest()[:FINGERPRINT_CHARS]


class SessionFileError(ValueError):
    """Raised when a session file cannot be used at all; names the file and the field."""


@dataclass(frozen=True)
class TaskSpec:
    """One task of a session. `checks`, `oracle` and `faults` are hidden from agents."""

    id: str
    template: str
    category: str
    difficulty: str
    text: str
    aliases: tuple[str, ...]
    budget: TaskBudget | None
    checks: Node | None
    oracle: tuple[tuple[Mapping[str, Any], ...], ...] | None
    error: str | None = None
    faults: TaskFaults | None = None  # hidden, like checks and oracle


@dataclass(frozen=True)
class Session:
    source: str
    id: str
    name: str
    family: str
    level: str
    index: int
    task_type: str
    scenario: Scenario
    tasks: tuple[TaskSpec, ...]
    data: Mapping[str, Any]

    @functools.cached_property
    def fingerprint(self) -> str:
        """Its session file's fingerprint (benchmark.authoring.fingerprint), worked out once:
        every task record carries it."""
        return text_fingerprint(dump_session(self.data))


def task_from_dict(k: int, raw: Any, scenario: Scenario) -> TaskSpec:
    """Task k of a session; an invalid task comes back with `error` set."""
    ident = raw.get("id") if isinstance(raw, Mapping) else None
    ident = ident if isinstance(ident, str) and ident else f"#{k + 1}"
    where = f"tasks[{k}] ({ident})"
    try:
        try:
            task = TaskFile.model_validate(raw)
        except ValidationError as error:
            first = error.errors(include_url=False)[0]
            raise ValueError(describe_error(first, raw, top=where)) from None
        try:
            checks = parse_tree(task.checks, scenario, path=f"{where}.checks")
        except CheckDefinitionError as error:
            raise ValueError(str(error)) from None
        oracle = None
        if task.oracle is not None:
            parse_plan(raw["oracle"], f"{where}.oracle")  # every step reads as its type
            oracle = tuple(tuple(phase) for phase in raw["oracle"])
        faults = task_faults(raw, [v.id for v in scenario.vehicles], where)
        budget = TaskBudget(task.budget.tool_calls, task.budget.sim_time_s)
        return TaskSpec(ident, task.template, task.category, task.difficulty, task.text,
                        tuple(task.aliases), budget, checks, oracle, faults=faults)
    except ValueError as error:
        text = raw.get("text") if isinstance(raw, Mapping) else None
        return TaskSpec(ident, str(raw.get("template", "custom")) if isinstance(raw, Mapping)
                        else "custom", "uncategorised", "medium",
                        text if isinstance(text, str) else "", (), None, None, None,
                        error=str(error))


def session_from_dict(data: Any, *, source: str = "<dict>") -> Session:
    """Build a Session; raises SessionFileError for a file that is not a usable session."""
    if not isinstance(data, Mapping):
        raise SessionFileError(f"{source}: the top level must be a JSON object")
    schema = data.get("schema")
    if schema != SCHEMA:
        hint = (" (it looks like a MultiUAV-Plat session: convert it with "
                "`mavswarm bench import`)" if schema is None and "drones" in data else "")
        raise SessionFileError(f"{source}: schema: expected {SCHEMA!r}, got "
                               f"{json.dumps(schema)}{hint}")
    try:
        header = SessionHeader.model_validate(data)
    except ValidationError as error:
        first = error.errors(include_url=False)[0]
        raise SessionFileError(f"{source}: {describe_error(first, data)}") from None
    try:
        scenario = scenario_from_model(header, data, source=source)
    except ScenarioError as error:
        raise SessionFileError(str(error)) from None
    tasks = tuple(task_from_dict(k, raw, scenario) for k, raw in enumerate(header.tasks))
    seen: set[str] = set()
    for task in tasks:
        if task.id in seen:
            raise SessionFileError(f"{source}: tasks: duplicate task id {task.id!r}")
        seen.add(task.id)
    return Session(source, header.id, str(data.get("name", header.id)), header.family,
                   header.level, header.index, scenario.task_type, scenario, tasks, data)


def read_session_json(path: str | Path) -> Any:
    """The parsed JSON of a session file; raises SessionFileError naming the file."""
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise SessionFileError(f"{source}: cannot read: {error}") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as error:
        raise SessionFileError(f"{source}: not valid JSON (truncated or corrupt?): "
                               f"{error}") from None


def load_session(path: str | Path) -> Session:
    """Read a mavswarm session file; raises SessionFileError naming the file and the field
    (`benchmark.authoring.importer.load_any_session` also takes MultiUAV-Plat files)."""
    return session_from_dict(read_session_json(path), source=str(path))


def dump_session(data: Mapping[str, Any]) -> str:
    """The canonical text of a session file: stable key order, one trailing newline."""
    return json.dumps(data, indent=1, ensure_ascii=False) + "\n"
