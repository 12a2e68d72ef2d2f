"""Template files: reading (errors name the file, the field and the reason), writing, and the
`Template` a file becomes (its build draws entities, then values, then fills the placeholders).
"""

from __future__ import annotations

import importlib
import json
import math
import random
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pydantic import ValidationError

from benchmark.authoring.template_files.model import TemplateFile, ValueSpec
from benchmark.authoring.template_files.placeholders import Filler

if TYPE_CHECKING:  # benchmark.authoring.templates loads its file templates through this module
    from benchmark.authoring.templates.base import SessionView, TaskDraft, Template

__all__ = ["TemplateFileError", "dump_template", "load_template", "load_templates",
           "parse_template", "read_template", "read_templates", "template_of"]


class TemplateFileError(ValueError):
    """A template file that cannot be used: the message names the file, field and reason."""

    field: str | None = None
    """The field to blame (``values[1].max``), where `parse_template` knows it."""


def _where(loc: Sequence[int | str]) -> str:
    out = ""
    for part in loc:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out or "(file)"


def _read_json(path: Path) -> Any:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except OSError as error:
        raise TemplateFileError(f"{path}: cannot be read: {error.strerror}") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise TemplateFileError(f"{path}: not JSON: {error}") from None


def _validated(raw: Any, where: str) -> TemplateFile:
    for loc, value in _numbers(raw, ()):
        if not math.isfinite(value):
            raise TemplateFileError(f"{where}: {_where(loc)}: {value} is not a finite number")
    try:
        model = TemplateFile.model_validate(raw)
    except ValidationError as error:
        first = error.errors()[0]
        reason = str(first["msg"]).removeprefix("Value error, ")
        raise TemplateFileError(f"{where}: {_where(first['loc'])}: {reason}") from None
    _check_tree(where, model)
    return model


def parse_template(text: str, source: str = "<text>") -> TemplateFile:
    """The validated model of a template file's text (an editor's); the TemplateFileError
    names `source`, the field (also as its `field`) and the reason."""
    def refused(field: str, reason: str) -> TemplateFileError:
        error = TemplateFileError(f"{source}: {field}: {reason}")
        error.field = field
        return error

    try:
        raw = json.loads(text)
    except json.JSONDecodeError as error:
        raise refused("(file)", f"not JSON: {error}") from None
    for loc, value in _numbers(raw, ()):
        if not math.isfinite(value):
            raise refused(_where(loc), f"{value} is not a finite number")
    try:
        model = TemplateFile.model_validate(raw)
    except ValidationError as error:
        first = error.errors()[0]
        raise refused(_where(first["loc"]),
                      str(first["msg"]).removeprefix("Value error, ")) from None
    try:
        _check_tree(source, model)
    except TemplateFileError as error:
        reason = str(error).removeprefix(f"{source}: ")
        field, _, why = reason.partition(": ")
        raise refused(field if why else "checks", why or reason) from None
    return model


def _numbers(data: Any, loc: tuple[int | str, ...]
             ) -> Iterator[tuple[tuple[int | str, ...], float]]:
    """Every float of parsed JSON with where it is (JSON text may say Infinity, NaN, 1e999)."""
    if isinstance(data, float):
        yield loc, data
    elif isinstance(data, dict):
        for key, value in data.items():
            yield from _numbers(value, (*loc, str(key)))
    elif isinstance(data, list):
        for k, value in enumerate(data):
            yield from _numbers(value, (*loc, k))


def read_template(path: str | Path) -> TemplateFile:
    """The validated model of one template file (``mavswarm.template/1``)."""
    path = Path(path)
    return _validated(_read_json(path), str(path))


def read_templates(path: str | Path) -> list[TemplateFile]:
    """The validated models of one file: a ``mavswarm.template/1`` file, or a template or a
    catalogue of templates in MultiUAV-Plat's layout
    (`benchmark.authoring.template_files.reference`; templates it excludes from random
    generation are left out)."""
    from benchmark.authoring.template_files.reference import (
        ReferenceTemplateError,
        is_reference_layout,
        reference_templates,
    )
    path = Path(path)
    raw = _read_json(path)
    if not is_reference_layout(raw):
        return [_validated(raw, str(path))]
    try:
        converted = reference_templates(raw, path)
    except ReferenceTemplateError as error:
        raise TemplateFileError(str(error)) from None
    return [_validated(data, where) for where, data in converted]


def _check_tree(path: str, model: TemplateFile) -> None:
    """The check tree's shape and endpoints (placeholders are filled per task)."""
    from benchmark.scoring.validators import CheckDefinitionError, parse_tree
    from benchmark.scoring.validators.tree import endpoints_used

    try:
        tree = parse_tree(_neutral(model.checks), None)
    except CheckDefinitionError as error:
        raise TemplateFileError(f"{path}: {error}") from None
    if not endpoints_used(tree):
        raise TemplateFileError(f"{path}: checks: the tree has no check")


def _neutral(data: Any) -> Any:
    """The tree with every placeholder string replaced by a value of the expected type's
    neutral form, so that its structure and endpoint names can be validated early."""
    if isinstance(data, dict):
        out = {k: _neutral(v) for k, v in data.items()}
        params = out.get("parameters")
        if isinstance(params, dict):
            out["parameters"] = {k: _sample(k, v) for k, v in params.items()}
        return out
    if isinstance(data, list):
        return [_neutral(v) for v in data]
    return data


def _sample(key: str, value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _sample(k, v) for k, v in value.items()}
    if not (isinstance(value, str) and value.startswith("{") and value.endswith("}")):
        return value
    if key.endswith("_ids"):
        return ["d1"]
    if key in ("mode", "expected_status"):
        return {"mode": "all_pairs", "expected_status": "hovering"}[key]
    if key.endswith("_id") or key == "content":
        return value  # distinct placeholders stand for distinct entities
    return 1.0


def _with_hooks(model: TemplateFile, where: str) -> Template:
    for k, spec in enumerate(model.values):
        if spec.call is not None:
            try:
                _hook(spec.call)
            except TemplateFileError as error:
                raise TemplateFileError(f"{where}: values[{k}].call: {error}") from None
    return template_of(model)


def load_template(path: str | Path) -> Template:
    """The `Template` of one ``mavswarm.template/1`` file (raises TemplateFileError; a hook
    that cannot be loaded is named with the file)."""
    return _with_hooks(read_template(path), str(path))


def load_templates(folder: str | Path) -> list[Template]:
    """Every template of a folder's ``*.json`` files (ours, or the reference's layout: one
    template or a catalogue per file), in file-name order; two templates of one id are
    refused."""
    folder = Path(folder)
    if not folder.is_dir():
        raise TemplateFileError(f"{folder}: not a folder of template files")
    out: list[Template] = []
    seen: dict[str, Path] = {}
    for path in sorted(folder.glob("*.json")):
        for model in read_templates(path):
            template = _with_hooks(model, str(path))
            if template.key in seen:
                raise TemplateFileError(f"{path}: id: {template.key!r} is also the id of "
                                        f"{seen[template.key]}")
            seen[template.key] = path
            out.append(template)
    return out


def dump_template(model: TemplateFile) -> str:
    """A template file's text (fields in the model's order, defaults left out)."""
    return json.dumps(model.model_dump(mode="json", exclude_defaults=True,
                                       exclude={"format"}) | {"format": model.format},
                      indent=2, ensure_ascii=False) + "\n"


# ------------------------------------------------------------------ building
_WORDS = {"drone": "drone", "area_target": "area target", "point_target": "fixed target",
          "moving_target": "moving target", "station": "charging station",
          "inspectable": "point or area target", "target": "target", "obstacle": "obstacle"}
_POOLS = {"drone": "drones", "area_target": "areas", "point_target": "points",
          "moving_target": "movers", "station": "stations"}


def _pool(view: SessionView, kind: str) -> list[Any]:
    if kind in _POOLS:
        return list(getattr(view, _POOLS[kind]))
    if kind == "inspectable":
        return [t for t in view.points if t.kind == "fixed"] + list(view.areas)
    if kind == "target":
        return list(view.scenario.world.targets)
    return list(view.scenario.world.obstacles)


def _entities(model: TemplateFile, view: SessionView, rng: random.Random
              ) -> tuple[dict[str, str], dict[str, Any]]:
    """Placeholders and objects of the entity groups: groups of one kind are drawn together,
    in the order their kind first appears."""
    from benchmark.authoring.templates.base import TemplateUnfit
    out: dict[str, str] = {}
    objects: dict[str, Any] = {}
    kinds = list(dict.fromkeys(g.kind for g in model.entities))
    for kind in kinds:
        groups = [g for g in model.entities if g.kind == kind]
        pool = _pool(view, kind)
        if not pool:
            raise TemplateUnfit(f"the session has no {_WORDS[kind]}")
        if model.distinct and len(pool) >= len(groups):
            chosen = rng.sample(pool, len(groups))
        elif model.distinct is True:
            raise TemplateUnfit(f"{len(groups)} distinct {_WORDS[kind]}s wanted, "
                                f"{len(pool)} here")
        else:
            chosen = [rng.choice(pool) for _ in groups]
        for group, entity in zip(groups, chosen, strict=True):
            out[f"{group.group}_id"], out[f"{group.group}_name"] = entity.id, entity.name
            where = getattr(entity, "position_m", None) or getattr(entity, "center_m", None)
            if where is not None:
                out[f"{group.group}_xy"] = f"({where[0]:.0f}, {where[1]:.0f})"
            objects[group.group] = entity
    return out, objects


def _hook(call: str) -> Any:
    module, _, name = call.partition(":")
    try:
        return getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as error:
        raise TemplateFileError(f"hook {call!r} cannot be loaded: {error}") from None


def _values(model: TemplateFile, view: SessionView, rng: random.Random,
            objects: dict[str, Any]) -> dict[str, Any]:
    values: dict[str, Any] = {}
    for spec in model.values:
        if spec.kind == "hook":
            assert spec.call is not None
            values.update(_hook(spec.call)(view, rng, dict(values), objects))
        else:
            values[spec.name] = _value(spec, view, rng)
    return values


def _value(spec: ValueSpec, view: SessionView, rng: random.Random) -> Any:
    if spec.kind == "choice":
        return rng.choice(spec.options)
    if spec.kind == "point":
        region = None if spec.region is None else view.region(*spec.region)
        return view.free_point(rng, clearance_m=spec.clearance_m, region=region)
    assert spec.min is not None and spec.max is not None
    if spec.kind == "int":
        lo, hi = round(spec.min), round(spec.max)
        return rng.randrange(lo, hi + 1, spec.step) if spec.step else rng.randint(lo, hi)
    return round(rng.uniform(spec.min, spec.max), spec.decimals)


def template_of(model: TemplateFile) -> Template:
    """The catalogue entry of a template file."""
    from benchmark.authoring.templates.base import TaskDraft, Template

    def build(view: SessionView, rng: random.Random) -> TaskDraft:
        entities, objects = _entities(model, view, rng)
        values = _values(model, view, rng, objects)
        filler = Filler(rng, view, entities, values)
        phrasings = [filler.text(p) for p in model.phrasings]
        plan = None if model.plan is None else filler.structure(model.plan, plan=True)
        checks = filler.structure(model.checks, plan=False)
        b = model.budget
        flight_m, hover_s = (float(filler.structure(v, plan=False)) if isinstance(v, str)
                             else v for v in (b.flight_m, b.hover_s))
        flight_m += b.flight_diagonals * math.hypot(view.map_w_m, view.map_h_m)
        steps = b.steps if isinstance(b.steps, int) else int(filler.structure(b.steps,
                                                                               plan=True))
        faults = None if model.faults is None else filler.structure(model.faults, plan=True)
        return TaskDraft(phrasings=phrasings, checks=checks, oracle=plan,  # type: ignore[arg-type]
                         flight_m=flight_m, hover_s=hover_s, steps=steps, faults=faults)

    def count(kind: str) -> int:
        return sum(1 for g in model.entities if g.kind == kind)

    return Template(model.id, model.category, model.difficulty, build,
                    drones=count("drone") if model.distinct is True else min(count("drone"), 1),
                    area_targets=count("area_target"), point_targets=count("point_target"),
                    stations=count("station"), families=tuple(model.families),
                    moving_targets=count("moving_target"), levels=tuple(model.levels))
