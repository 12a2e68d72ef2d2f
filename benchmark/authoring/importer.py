"""Import of MultiUAV-Plat session files, tasks and hidden check trees included, into
mavswarm's session schema, so their missions run here with the same checks.

Entities and environment are kept in the reference's entity layout (which mavswarm sessions
use too). Each task keeps its text (`content`), its phrasings (`content_aliases`) and its check
tree (`execution_check_apis`) with endpoint names stripped of ``/check/``. Parameters the
reference ignores (names no endpoint declares) are dropped, each with a note. A task whose tree
names an unknown endpoint or holds an invalid value is written unchanged: loading the file
reports it (file, task, field) and a run records it as a task error without stopping.
Imported tasks carry no oracle plan: `bench import` proves each with the oracle's plan derived
from its checks (`benchmark.running.proof`) and writes the verdict into the task's ``proof`` field
(``proved``, and for a task not proved the ``leaf``, its ``endpoint`` and the ``reason``), so
that no task is taken for solvable without being flown.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from benchmark.authoring.session_file import (
    SCHEMA,
    Session,
    SessionFileError,
    dump_session,
    read_session_json,
    session_from_dict,
)
from benchmark.scoring.validators import ENDPOINTS
from benchmark.scoring.validators.endpoint import IGNORED_PARAMETERS
from emulator.scenario import ScenarioError, scenario_from_dict

ProveTasks = Callable[[Session], Sequence[Mapping[str, Any]]]
"""Flies every task of a session and gives each task's proof as JSON, in task order."""

__all__ = ["ProveTasks", "SessionImportError", "import_session", "import_session_file",
           "load_any_session", "reference_tree"]

DEFAULT_BUDGET = {"tool_calls": 120, "sim_time_s": 1800.0}
ENTITY_KEYS = ("drones", "targets", "obstacles", "environment")


class SessionImportError(ValueError):
    """Raised when a file is not a MultiUAV-Plat session; names the file and the field."""


def _endpoint_name(raw: object) -> object:
    if isinstance(raw, str) and raw.startswith("/check/"):
        return raw[len("/check/"):]
    return raw


def _convert_tree(node: Any, where: str, notes: list[str]) -> Any:
    if not isinstance(node, Mapping):
        return node
    if "endpoint" in node:
        name = _endpoint_name(node["endpoint"])
        out = dict(node, endpoint=name)
        params = node.get("parameters")
        endpoint = ENDPOINTS.get(name) if isinstance(name, str) else None
        if endpoint is not None and isinstance(params, Mapping):
            known = {p.name for p in endpoint.params} | IGNORED_PARAMETERS | endpoint.ignored
            dropped = sorted(k for k in params if k not in known)
            for key in dropped:
                notes.append(f"{where}.parameters.{key}: not a parameter of {name}; dropped "
                             f"(the reference ignores it)")
            out["parameters"] = {k: v for k, v in params.items() if k not in dropped}
        return out
    checks = node.get("checks")
    if isinstance(checks, list):
        return dict(node, checks=[_convert_tree(c, f"{where}.checks[{k}]", notes)
                                  for k, c in enumerate(checks)])
    return dict(node)


def reference_tree(node: Any, where: str, notes: list[str]) -> Any:
    """A reference check tree in mavswarm's form: endpoint names without ``/check/``,
    parameters no endpoint declares dropped (each with a note in `notes`)."""
    return _convert_tree(node, where, notes)


def _convert_task(k: int, raw: Any, source: str, notes: list[str]) -> dict[str, Any]:
    if not isinstance(raw, Mapping):
        raise SessionImportError(f"{source}: tasks[{k}]: expected an object")
    ident = str(raw.get("id") or f"t{k + 1:02d}")
    where = f"tasks[{k}] ({ident})"
    tree = raw.get("execution_check_apis")
    checks = ({"logic": "and", "checks": []} if tree in (None, {}, [])
              else _convert_tree(tree, f"{where}.checks", notes))
    difficulty = raw.get("difficulty", "medium")
    if difficulty not in ("easy", "medium", "hard"):
        notes.append(f"{where}.difficulty: {difficulty!r} read as 'medium'")
        difficulty = "medium"
    aliases = [a for a in raw.get("content_aliases") or [] if isinstance(a, str)]
    origin = str(raw.get("originated_from") or raw.get("name") or "imported")
    return {"id": ident, "template": f"imported:{raw.get('name', ident)}",
            "category": "imported", "difficulty": difficulty,
            "text": str(raw.get("content") or ""), "aliases": aliases,
            "budget": dict(DEFAULT_BUDGET), "checks": checks, "oracle": None,
            "source": origin}


def import_session(data: Any, *, source: str = "<dict>") -> tuple[dict[str, Any], list[str]]:
    """(mavswarm session object, notes) from a parsed MultiUAV-Plat session."""
    session, _, notes = _convert(data, source)
    return session, notes


def _convert(data: Any, source: str) -> tuple[dict[str, Any], Session, list[str]]:
    """The mavswarm session object, the Session it loads as, and the notes."""
    if not isinstance(data, Mapping):
        raise SessionImportError(f"{source}: the top level must be a JSON object")
    if data.get("schema") == SCHEMA:
        raise SessionImportError(f"{source}: already a mavswarm session")
    if not isinstance(data.get("drones"), list):
        raise SessionImportError(f"{source}: drones: missing or not a list (not a MultiUAV-Plat "
                           f"session file?)")
    try:
        scenario = scenario_from_dict(data, source=source)
    except ScenarioError as error:
        raise SessionImportError(str(error)) from None
    notes: list[str] = list(scenario.notes)
    tasks_raw = data.get("tasks") or []
    if not isinstance(tasks_raw, list):
        raise SessionImportError(f"{source}: tasks: expected a list")
    tasks = [_convert_task(k, t, source, notes) for k, t in enumerate(tasks_raw)]
    ident = str(data.get("id") or Path(source).stem)
    session: dict[str, Any] = {
        "schema": SCHEMA, "id": ident, "family": scenario.task_type, "level": "imported",
        "index": 0, "seed": None, "name": str(data.get("name", ident)),
        "description": str(data.get("description") or f"Imported from {Path(source).name}"),
        "task_type": scenario.task_type,
        "map_size_m": [float(data.get("canvas_width", 1024)),
                       float(data.get("canvas_height", 768))],
        "safety_margin_m": float(data.get("safety_margin_m", 2.0)),
    }
    if "origin" in data:
        session["origin"] = data["origin"]
    for key in ENTITY_KEYS:
        if data.get(key) is not None:
            session[key] = data[key]
    session["tasks"] = tasks
    loaded = session_from_dict(session, source=source)
    for task in loaded.tasks:
        if task.error:
            notes.append(f"task {task.id} will be recorded as a task error: {task.error}")
    return session, loaded, notes


def import_session_file(path: str | Path, out_dir: str | Path, *,
                        taken: set[str] | None = None, prove: ProveTasks | None = None
                        ) -> tuple[Path, list[str]]:
    """Convert one file into out_dir/<id>.json; returns its path and the notes. An id already
    in `taken` (the files converted before it in the same import) gets a numbered suffix, so
    no file overwrites another; the id written is added to `taken`. With `prove` (the oracle
    flying every task: benchmark.running.proof), each task's ``proof`` field says how it
    went."""
    source = str(path)
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as error:
        raise SessionImportError(f"{source}: cannot read: {error}") from None
    except json.JSONDecodeError as error:
        raise SessionImportError(f"{source}: not valid JSON: {error}") from None
    session, notes = import_session(data, source=source)
    if taken is not None:
        ident, n = session["id"], 2
        while session["id"] in taken:
            session["id"], n = f"{ident}-{n}", n + 1
        if session["id"] != ident:
            notes.append(f"id {ident!r} was taken by an earlier file of this import; written "
                         f"as {session['id']!r}")
        taken.add(session["id"])
    if prove is not None:
        proofs = prove(session_from_dict(session, source=source))
        for task, proof in zip(session["tasks"], proofs, strict=True):
            task["proof"] = dict(proof)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    target = out / f"{session['id']}.json"
    target.write_text(dump_session(session), encoding="utf-8")
    return target, notes


def load_any_session(path: str | Path) -> tuple[Session, list[str]]:
    """A session from a mavswarm session file, or from a MultiUAV-Plat file converted in memory
    as `bench import` would; with the notes on what was read differently. Raises
    SessionFileError naming the file and the field."""
    source = str(path)
    data = read_session_json(path)
    if isinstance(data, Mapping) and data.get("schema") is None and "drones" in data:
        try:
            _, loaded, notes = _convert(data, source)
        except SessionImportError as error:
            raise SessionFileError(str(error)) from None
        return loaded, notes
    session = session_from_dict(data, source=source)
    return session, list(session.scenario.notes)
