"""Benchmark generation: seeded worlds, 20 tasks per session drawn from the templates, and
every task proved by the oracle flying it through the emulator.

For each task slot the generator draws a template (weighted by family, at most twice per
session) and its parameters from a generator seeded by (session seed, slot, attempt). With
verification on, the session's swarm runs the tasks in order as a benchmark run would; a task
the oracle fails is taken back (the drones are put back where the task started) and redrawn
with the next attempt. The result depends on the seed alone.
"""

from __future__ import annotations

import hashlib
import math
import random
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from benchmark.authoring.scenarios import SESSION_INDICES, generate_world
from benchmark.authoring.session_file import (
    Session,
    dump_session,
    session_from_dict,
)
from benchmark.authoring.task_faults import task_faults
from benchmark.authoring.templates import CATALOGUE, SessionView, Template, TemplateUnfit
from benchmark.scoring.validators import leaf_count, parse_tree

__all__ = [
    "MAX_ATTEMPTS",
    "ORACLE_TRIES",
    "TASKS_PER_SESSION",
    "Drawer",
    "GenerationError",
    "ProveTasks",
    "build_task",
    "catalogue_with",
    "generate_for_world",
    "generate_session",
    "write_session",
]

TASKS_PER_SESSION = 20
MAX_ATTEMPTS = 8
ORACLE_TRIES = 2
MAX_SAME_TEMPLATE = 2
CRUISE_ESTIMATE_M_S = 8.0
CATEGORY_WEIGHTS = {
    "area_search": {"search": 4.0},
    "area_assignment_and_patrol": {"search": 3.0, "navigation": 2.0},
    "target_assignment": {"multi_drone_coordination": 3.0, "search": 2.0},
    "target_tracking": {"target_tracking": 12.0},
    "resilience": {"resilience": 12.0},
}


ProveTasks = Callable[[dict[str, Any], Session, "Drawer", int, Callable[[str], None]],
                      list[dict[str, Any]]]
"""Draws `count` tasks for a world's empty session with a drawer and keeps only those proved
(benchmark.running.generation.verified_tasks flies each with the oracle)."""


class GenerationError(RuntimeError):
    """Raised when a session cannot be filled with oracle-passable tasks."""


def _budget(draft_flight_m: float, hover_s: float, steps: int) -> dict[str, Any]:
    sim_s = 300.0 + 3.0 * draft_flight_m / CRUISE_ESTIMATE_M_S + 2.0 * hover_s
    return {"tool_calls": 30 + 4 * steps, "sim_time_s": float(60 * math.ceil(sim_s / 60.0))}


def build_task(template: Template, view: SessionView, rng: random.Random, task_id: str
               ) -> dict[str, Any]:
    """One task object from a template (raises TemplateUnfit)."""
    draft = template.build(view, rng)
    parse_tree(draft.checks, view.scenario)  # a template bug surfaces here, not in a run
    task = {"id": task_id, "template": template.key, "category": template.category,
            "difficulty": template.difficulty, "text": draft.phrasings[0],
            "aliases": draft.phrasings[1:],
            "budget": _budget(draft.flight_m, draft.hover_s, draft.steps),
            "checks": draft.checks, "oracle": draft.oracle}
    if draft.faults is not None:
        task_faults(task | {"faults": draft.faults}, [v.id for v in view.drones])  # checked
        task["faults"] = draft.faults
    return task


def catalogue_with(folders: Sequence[Path] = (), *, replace: bool = False
                   ) -> tuple[Template, ...]:
    """The built-in templates plus those of the template-file folders (or only the latter,
    with replace); an id used twice is refused naming the file."""
    from benchmark.authoring.template_files import TemplateFileError, load_templates
    out = [] if replace else list(CATALOGUE)
    for folder in folders:
        for template in load_templates(folder):
            if any(t.key == template.key for t in out):
                raise TemplateFileError(f"{folder}: template id {template.key!r} is already "
                                        f"in the catalogue")
            out.append(template)
    if not out:
        raise GenerationError("no templates to draw from")
    return tuple(out)


class Drawer:
    """Template choice for each slot, and parameter draws for each attempt."""

    def __init__(self, family: str, seed: int, view: SessionView, level: str = "",
                 catalogue: Sequence[Template] = CATALOGUE) -> None:
        self.view = view
        self.seed = seed
        self.fitting = [t for t in catalogue if t.fits(view)
                        and (not t.levels or level in t.levels)]
        if not self.fitting:
            raise GenerationError("no template fits this session")
        weights = CATEGORY_WEIGHTS.get(family, {})
        self.weights = [weights.get(t.category, 1.0) for t in self.fitting]
        self.used: dict[str, int] = {}

    def template_for(self, slot: int, attempt: int) -> Template:
        rng = random.Random(f"{self.seed}/template/{slot}/{attempt}")
        pool = [(t, w) for t, w in zip(self.fitting, self.weights, strict=True)
                if self.used.get(t.key, 0) < MAX_SAME_TEMPLATE] or list(
                    zip(self.fitting, self.weights, strict=True))
        return rng.choices([t for t, _ in pool], [w for _, w in pool])[0]

    def draw(self, slot: int, attempt: int) -> dict[str, Any]:
        """Attempts 0-2 redraw one template's parameters; later ones change template."""
        template = self.template_for(slot, attempt // 3)
        rng = random.Random(f"{self.seed}/task/{slot}/{attempt}")
        task = build_task(template, self.view, rng, f"t{slot + 1:02d}")
        return task

    def accept(self, task: dict[str, Any]) -> None:
        self.used[task["template"]] = self.used.get(task["template"], 0) + 1


def _view(world: dict[str, Any], session: Session) -> SessionView:
    w, h = world["map_size_m"]
    return SessionView(world["family"], session.scenario, float(w), float(h))


def _unverified_tasks(drawer: Drawer, count: int) -> list[dict[str, Any]]:
    tasks = []
    for slot in range(count):
        for attempt in range(MAX_ATTEMPTS):
            try:
                raw = drawer.draw(slot, attempt)
            except TemplateUnfit:
                continue
            drawer.accept(raw)
            tasks.append(raw)
            break
        else:
            raise GenerationError(f"slot {slot + 1}: no template could be built")
    return tasks


def generate_session(family: str, level: str, index: int, *, prove: ProveTasks | None = None,
                     tasks: int = TASKS_PER_SESSION,
                     progress: Callable[[str], None] = print, secret: str = "",
                     catalogue: Sequence[Template] = CATALOGUE,
                     max_index: int = SESSION_INDICES[-1], drones: int = 0,
                     map_size_m: float = 0.0) -> dict[str, Any]:
    """The full session object for (family, level, index), drawn from the secret's seeds
    when one is given (a private split), with another drone count or square map side when
    given; its tasks proved by `prove` when one is given (benchmark.running.generation proves
    them with the oracle)."""
    world = generate_world(family, level, index, secret=secret, max_index=max_index,
                           drones=drones, map_size_m=map_size_m)
    return _with_tasks(world, int(world["seed"]), prove, tasks, progress, catalogue)


def generate_for_world(world: dict[str, Any], *, secret: str = "",
                       prove: ProveTasks | None = None,
                       tasks: int = TASKS_PER_SESSION,
                       progress: Callable[[str], None] = print,
                       catalogue: Sequence[Template] = CATALOGUE) -> dict[str, Any]:
    """Tasks drawn for a world of one's own (a session object; its tasks are replaced),
    seeded by the secret and the world's id."""
    label = f"mavswarm/world/{secret}/{world.get('id', '')}".encode()
    seed = int.from_bytes(hashlib.sha256(label).digest()[:8], "big") >> 11
    world = {**world, "tasks": []}
    world.setdefault("description", "")
    return _with_tasks(world, seed, prove, tasks, progress, catalogue)


def _with_tasks(world: dict[str, Any], seed: int, prove: ProveTasks | None, tasks: int,
                progress: Callable[[str], None], catalogue: Sequence[Template]
                ) -> dict[str, Any]:
    family, level = str(world.get("family", "")), str(world.get("level", ""))
    empty = session_from_dict({**world, "tasks": []}, source=str(world.get("id", "<world>")))
    view = _view(world, empty)
    drawer = Drawer(family, seed, view, level, catalogue)
    if prove is not None:
        drawn = prove(world, empty, drawer, tasks, progress)
    else:
        drawn = _unverified_tasks(drawer, tasks)
    session = {**world, "tasks": drawn}
    checks = sum(leaf_count(parse_tree(t["checks"], view.scenario)) for t in drawn)
    session["description"] = f"{world['description']} {len(drawn)} tasks, {checks} checks."
    return session


def write_session(session: dict[str, Any], out_dir: Path) -> Path:
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / f"{session['id']}.json"
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(dump_session(session), encoding="utf-8")
    tmp.replace(path)
    return path
