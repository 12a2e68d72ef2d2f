"""The task and template editor's server half (operators and admins): template files listed,
read and validated as text; a template's tasks drawn on the world being edited (with the
entities each task names and its check tree); every task of an edited world re-checked (which
still parse and can be planned, and else which leaf fails and why); templates saved into the
editor's save folder.

Templates are the built-in files (`benchmark/authoring/templates/files`) and those saved under the
save folder's `templates/`. A template written on the page may call only the hooks the
built-in template files call: a page never names code to import.
"""

from __future__ import annotations

import functools
import json
import random
import re
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import shapely

from benchmark.authoring.generate import build_task
from benchmark.authoring.session_file import SessionFileError, session_from_dict, task_from_dict
from benchmark.authoring.template_files import (
    TemplateFile,
    TemplateFileError,
    dump_template,
    template_of,
)
from benchmark.authoring.template_files.loader import parse_template
from benchmark.authoring.templates import SessionView, TemplateUnfit
from benchmark.authoring.templates.common import FILES
from benchmark.scoring.validators import CheckDefinitionError, parse_tree, tree_to_json
from benchmark.scoring.validators.tree import Leaf, Node
from console.editor import EditorError, write_in_folder
from swarm_agents.oracle.derive import Unplannable, derive_plan

__all__ = ["BUILT_IN_DIR", "SAVED_TEMPLATES", "TemplateTextError", "built_in_hooks",
           "check_template", "instantiate", "recheck", "save_template", "template_listing",
           "template_text"]

BUILT_IN_DIR = FILES  # the built-in template files
SAVED_TEMPLATES = "templates"
_UNFILLED = re.compile(r"\{[A-Za-z][A-Za-z0-9_.:]*\}")
TASK_LISTS = ("drones", "targets", "obstacles")


class TemplateTextError(ValueError):
    """A template text refused: the message names the field and the reason; `field` is that
    field's path (``values[1]``, ``checks[0].endpoint``)."""

    def __init__(self, message: str, field: str | None = None) -> None:
        super().__init__(message)
        self.field = field

    def to_json(self) -> dict[str, Any]:
        return {"ok": False, "error": str(self), "field": self.field}


# ------------------------------------------------------------------ listing and reading
def _files(root: Path) -> Iterator[tuple[str, Path]]:
    for path in sorted(BUILT_IN_DIR.glob("*.json")):
        yield "built-in", path
    saved = root / SAVED_TEMPLATES
    if saved.is_dir():
        for path in sorted(saved.glob("*.json")):
            if path.is_file():
                yield "saved", path


def template_listing(root: Path) -> list[dict[str, Any]]:
    """Every template file (`id`: its name without .json, what `template_text` reads):
    built-in ones, then those saved in `root`'s templates folder (a saved file that does not
    load is listed with its error)."""
    out: list[dict[str, Any]] = []
    for source, path in _files(root):
        entry: dict[str, Any] = {"id": path.stem, "source": source, "file": path.name}
        try:
            model = parse_template(path.read_text(encoding="utf-8"), path.name)
            entry.update(category=model.category, difficulty=model.difficulty,
                         description=model.description)
            if model.id != path.stem:  # read back by its file's name
                entry["template_id"] = model.id
        except (OSError, UnicodeDecodeError, TemplateFileError) as error:
            entry["error"] = str(error)
        out.append(entry)
    return out


def template_text(ident: str, root: Path) -> dict[str, Any] | None:
    """The text of template `ident` (a saved one before a built-in one of that id); None when
    there is none. Templates are named by id, never by a path."""
    found = None
    for source, path in _files(root):
        if path.stem == ident:
            found = (source, path)
    if found is None:
        return None
    source, path = found
    return {"id": ident, "source": source, "file": path.name,
            "text": path.read_text(encoding="utf-8")}


# ------------------------------------------------------------------ validating
@functools.cache
def built_in_hooks() -> frozenset[str]:
    """The hooks (module:function) the built-in template files call."""
    calls: set[str] = set()
    for path in BUILT_IN_DIR.glob("*.json"):
        raw = json.loads(path.read_text(encoding="utf-8"))
        calls.update(str(v["call"]) for v in raw.get("values", []) if v.get("call"))
    return frozenset(calls)


def check_template(text: str) -> TemplateFile:
    """The model of a template text; TemplateTextError names the field and the reason."""
    try:
        model = parse_template(text, "template")
    except TemplateFileError as error:
        raise TemplateTextError(str(error), error.field) from None
    for k, spec in enumerate(model.values):
        if spec.call is not None and spec.call not in built_in_hooks():
            raise TemplateTextError(f"template: values[{k}].call: {spec.call!r} is not a "
                                    f"built-in hook (one of {', '.join(sorted(built_in_hooks()))})",
                                    f"values[{k}].call")
    return model


# ------------------------------------------------------------------ drawing tasks
def _world(session: Any) -> tuple[dict[str, Any], SessionView]:
    if not isinstance(session, Mapping):
        raise EditorError("the session must be a JSON object")
    world = {**session, "tasks": []}
    try:
        empty = session_from_dict(world, source="session")
    except SessionFileError as error:
        raise EditorError(str(error)) from None
    w, h = world["map_size_m"]
    return dict(session), SessionView(str(world.get("family", "")), empty.scenario,
                                      float(w), float(h))


def _ids(value: Any) -> Iterator[str]:
    if isinstance(value, str):
        yield value
    elif isinstance(value, list | tuple):
        for item in value:
            yield from _ids(item)


def _points(value: Any) -> Iterator[list[float]]:
    if isinstance(value, Mapping):
        x, y = value.get("x"), value.get("y")
        if isinstance(x, int | float) and isinstance(y, int | float):
            yield [float(x), float(y)]
        for inner in value.values():
            if isinstance(inner, Mapping):
                yield from _points(inner)


def _leaves(node: Node, path: str = "checks") -> Iterator[tuple[str, Leaf]]:
    if isinstance(node, Leaf):
        yield path, node
        return
    for k, child in enumerate(node.checks):
        yield from _leaves(child, f"{path}[{k}]")


def task_entities(tree: Node, session: Mapping[str, Any]) -> dict[str, Any]:
    """The drones, targets and obstacles a check tree names, and the points it names."""
    known = {name: {str(e.get("id")) for e in session.get(name) or [] if isinstance(e, Mapping)}
             for name in TASK_LISTS}
    named: dict[str, list[str]] = {name: [] for name in TASK_LISTS}
    points: list[list[float]] = []
    for _, leaf in _leaves(tree):
        for key, value in leaf.parameters.items():
            if key.endswith(("_id", "_ids", "_to", "from")) or key in ("to", "target", "drones"):
                for ident in _ids(value):
                    for name in TASK_LISTS:
                        if ident in known[name] and ident not in named[name]:
                            named[name].append(ident)
        points.extend(p for p in _points(dict(leaf.parameters)) if p not in points)
    return {**named, "points": points}


def instantiate(session: Any, text: str, *, count: int = 1, seed: int = 1) -> dict[str, Any]:
    """`count` tasks of the template `text` drawn on the session's world (seeded by `seed`,
    the template's id and the task's slot), each with the entities its checks name and its
    check tree and its re-check (as `recheck`); a draw the world cannot take is answered with
    why."""
    model = check_template(text)
    data, view = _world(session)
    template = template_of(model)
    used = {str(t.get("id")) for t in data.get("tasks") or [] if isinstance(t, Mapping)}
    tasks: list[dict[str, Any]] = []
    unfit: list[str] = []
    k = 0
    for slot in range(count):
        while f"t{k + 1:02d}" in used:
            k += 1
        ident = f"t{k + 1:02d}"
        used.add(ident)
        rng = random.Random(f"mavswarm/editor/{seed}/{model.id}/{slot}")
        try:
            task = build_task(template, view, rng, ident)
        except TemplateUnfit as error:
            unfit.append(f"task {slot + 1}: {error}")
            continue
        except (CheckDefinitionError, ValueError) as error:
            unfit.append(f"task {slot + 1}: the template does not fill in: {error}")
            continue
        tree = parse_tree(task["checks"], view.scenario)
        check = _recheck_one(slot, task, view)
        tasks.append({"task": task, "entities": task_entities(tree, data),
                      "tree": tree_to_json(tree),
                      "check": {k: check[k] for k in ("solvable", "leaf", "endpoint", "reason")}})
    if not tasks:
        raise TemplateTextError(f"template {model.id!r} cannot be drawn on this world: "
                                + "; ".join(dict.fromkeys(unfit)))
    notes = []
    if model.families and view.family not in model.families:
        notes.append(f"written for the families {', '.join(model.families)}; this world's is "
                     f"{view.family!r}")
    texts = [t["task"]["text"] for t in tasks] + [a for t in tasks for a in t["task"]["aliases"]]
    unfilled = sorted({m for text in texts for m in _UNFILLED.findall(text)})
    if unfilled:
        notes.append(f"placeholders left unfilled in the phrasings: {', '.join(unfilled)} (no "
                     "entity group or value of that name)")
    note = "; ".join(notes)
    return {"template": model.id, "tasks": tasks, "unfit": unfit, "note": note}


# ------------------------------------------------------------------ re-checking
def _place_problem(path: str, leaf: Leaf, view: SessionView) -> str | None:
    """Why a position a leaf names cannot be flown to on this world (None: it can)."""
    p = leaf.parameters
    x, y = p.get("x"), p.get("y")
    if not (isinstance(x, int | float) and isinstance(y, int | float)):
        return None
    z = p.get("z")
    z_m = float(z) if isinstance(z, int | float) else 10.0
    drone = next((v for v in view.drones if v.id == p.get("drone_id")), None)
    if drone is not None and z_m > drone.max_altitude_m:
        return (f"{z_m:g} m is above {drone.id}'s maximum altitude of "
                f"{drone.max_altitude_m:g} m")
    if not (0.0 <= x <= view.map_w_m and 0.0 <= y <= view.map_h_m):
        return f"({x:g}, {y:g}) is outside the {view.map_w_m:g} x {view.map_h_m:g} m map"
    world = view.scenario.world
    margin_m = world.safety_margin_m
    spot = shapely.Point(float(x), float(y))
    for obstacle in world.obstacles:
        above = obstacle.height_m > 0.0 and z_m > obstacle.height_m + margin_m
        if not above and obstacle.footprint.buffer(margin_m).intersects(spot):
            return (f"({x:g}, {y:g}) at {z_m:g} m is inside obstacle {obstacle.id} or its "
                    f"{margin_m:g} m safety margin")
    return None


def _recheck_one(k: int, raw: Any, view: SessionView) -> dict[str, Any]:
    ident = raw.get("id", f"#{k + 1}") if isinstance(raw, Mapping) else f"#{k + 1}"
    out: dict[str, Any] = {"index": k, "id": ident, "solvable": False, "leaf": None,
                           "endpoint": None, "reason": None}
    spec = task_from_dict(k, raw, view.scenario)
    if spec.error is not None or spec.checks is None:
        return {**out, "reason": spec.error or "the task has no checks"}
    for path, leaf in _leaves(spec.checks):
        problem = _place_problem(path, leaf, view)
        if problem is not None:
            return {**out, "leaf": path, "endpoint": leaf.endpoint, "reason": problem}
    faulted = sorted({f.drone for f in spec.faults.failures}) if spec.faults else []
    try:
        derive_plan(spec.checks, view.scenario, {}, faulted=faulted)
    except Unplannable as error:
        if spec.oracle is None:  # a hand plan may still fly it: the proof tells
            return {**out, "leaf": error.path, "endpoint": error.endpoint,
                    "reason": error.reason}
    return {**out, "solvable": True}


def recheck(session: Any) -> dict[str, Any]:
    """Every task of the session against its (edited) world: which still parse, name places
    that can be flown to and can be planned (`solvable`), and for the others the leaf that
    fails (its path in the check tree, its endpoint) and why."""
    data, view = _world(session)
    results = [_recheck_one(k, raw, view) for k, raw in enumerate(data.get("tasks") or [])]
    return {"tasks": results, "solvable": sum(1 for r in results if r["solvable"]),
            "total": len(results)}


# ------------------------------------------------------------------ saving
def save_template(text: str, root: Path) -> dict[str, Any]:
    """Validate the template text, then write it (in the file format's layout) as
    `templates/<id>.json` in `root` (a built-in template's id is refused)."""
    model = check_template(text)
    if (BUILT_IN_DIR / f"{model.id}.json").exists():
        raise TemplateTextError(f"template id {model.id!r} is a built-in template's: save the "
                                f"edited copy under a new id (e.g. {model.id}_edit)", "id")
    folder = root / SAVED_TEMPLATES
    written = write_in_folder(dump_template(model), Path(f"{model.id}.json"), folder)
    return {"ok": True, "id": model.id, "path": str(written)}

