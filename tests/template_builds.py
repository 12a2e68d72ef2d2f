"""Every task draft of the search, coordination and assignment templates over the generated
benchmark worlds (one world per family and level, 30 seeds), built once per test process and
shared by the template tests."""

from __future__ import annotations

import random
from collections.abc import Iterator
from typing import Any

from benchmark.authoring.scenarios import FAMILIES, LEVELS, generate_world
from benchmark.authoring.templates import assignment, coordination, search
from benchmark.authoring.templates.base import SessionView, TaskDraft, Template, TemplateUnfit
from emulator.scenario import scenario_from_dict

TEMPLATES: tuple[Template, ...] = (*search.TEMPLATES, *coordination.TEMPLATES,
                                   *assignment.TEMPLATES)
BY_KEY = {t.key: t for t in TEMPLATES}
SEEDS = range(30)

_VIEWS: dict[tuple[str, str], SessionView] = {}
_BUILDS: dict[str, list[tuple[SessionView, int, TaskDraft]]] = {}
UNFIT: dict[str, int] = {}


def view_of(family: str, level: str) -> SessionView:
    if (family, level) not in _VIEWS:
        world = generate_world(family, level, 1)
        w, h = world["map_size_m"]
        _VIEWS[family, level] = SessionView(family, scenario_from_dict(world), float(w),
                                            float(h))
    return _VIEWS[family, level]


def views() -> Iterator[SessionView]:
    for family in FAMILIES:
        for level in LEVELS:
            yield view_of(family, level)


def drafts_built(key: str) -> list[tuple[SessionView, int, TaskDraft]]:
    """Every draft of the template over all fitting sessions and seeds (cached)."""
    if key not in _BUILDS:
        template, out, unfit = BY_KEY[key], [], 0
        for view in views():
            if not template.fits(view):
                continue
            for seed in SEEDS:
                try:
                    out.append((view, seed, template.build(view, random.Random(seed))))
                except TemplateUnfit:
                    unfit += 1
        _BUILDS[key], UNFIT[key] = out, unfit
    return _BUILDS[key]


def drafts(key: str) -> list[TaskDraft]:
    return [draft for _view, _seed, draft in drafts_built(key)]


def check_leaves(node: dict[str, Any]) -> Iterator[dict[str, Any]]:
    if "endpoint" in node:
        yield node
    else:
        for child in node["checks"]:
            yield from check_leaves(child)


def plan_ops(draft: TaskDraft) -> Iterator[dict[str, Any]]:
    for phase in draft.oracle:
        yield from phase
