"""Messages for a session file's validation errors: `label: field reason`, where the label
names the entity (`drones[3] (id d4)`, `environment`, `session`) and the field is its path
inside it (`position.z`, `vertices[1]`), the reason in words (`must be > 0, got -2`)."""

from __future__ import annotations

import json
from typing import Any

from pydantic_core import ErrorDetails

from emulator.world import OBSTACLE_KINDS, TARGET_KINDS

__all__ = ["ENTITY_LISTS", "describe_error", "entity_label", "show"]

ENTITY_LISTS = ("drones", "targets", "obstacles")


def show(value: object) -> str:
    """A field value as it reads in JSON, shortened."""
    try:
        text = json.dumps(value)
    except (TypeError, ValueError):
        text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


_TAGS = {"targets": TARGET_KINDS, "obstacles": OBSTACLE_KINDS}  # the unions' tags (tested)


def entity_label(data: Any, key: str, index: int | None = None) -> str:
    """`drones[3] (id d4)`, `environment (id e1)`, `session`: where in the file."""
    label = key if index is None else f"{key}[{index}]"
    try:
        raw = data[key] if index is None else data[key][index]
    except (KeyError, IndexError, TypeError):
        return label
    ident = raw.get("id") if isinstance(raw, dict) else None
    return f"{label} (id {ident})" if isinstance(ident, str) and ident else label


def _path(loc: tuple[int | str, ...]) -> str:
    out = ""
    for part in loc:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


def _reason(error: ErrorDetails, field: str) -> str:
    kind, got, ctx = error["type"], show(error["input"]), error.get("ctx", {})
    if kind == "missing":
        return "is required"
    if kind in ("float_type", "float_parsing", "int_type", "int_from_float"):
        return f"must be {'an integer' if kind.startswith('int') else 'a number'}, got {got}"
    if kind == "finite_number":
        return f"must be finite, got {got}"
    bounds = {"greater_than": ">", "greater_than_equal": ">=", "less_than": "<",
              "less_than_equal": "<="}
    if kind in bounds:
        limit = next(iter(ctx.values()))
        return f"must be {bounds[kind]} {limit:g}, got {got}"
    if kind == "non_empty_string":
        return f"must be a non-empty string, got {got}"
    if kind == "string_type":
        return f"must be a string, got {got}"
    if kind == "bool_type":
        return f"must be true or false, got {got}"
    if kind in ("model_type", "model_attributes_type", "dict_type", "dataclass_type"):
        if ctx.get("class_name") == "PointEntity":
            return f"must be an object with numbers x and y, got {got}"
        return f"must be a JSON object, got {got}"
    if kind == "list_type":
        points = field.rsplit(".", 1)[-1] in ("vertices", "moving_path")
        return f"must be a list{' of {x, y} points' if points else ''}, got {got}"
    if kind == "too_short":
        least = ctx.get("min_length", 1)
        return f"must list at least {'one entry' if least == 1 else f'{least} entries'}"
    if kind == "literal_error":
        return f"must be one of {ctx.get('expected', '')}; got {got}"
    if kind == "value_error":
        return str(error["msg"]).removeprefix("Value error, ")
    if kind in ("entity_field", "polygon", "wind_direction") or kind.startswith("mavswarm_"):
        return str(error["msg"])
    return f"is invalid: {error['msg']}"


def describe_error(error: ErrorDetails, data: Any, top: str = "session") -> str:
    """`label: field reason` for one pydantic error of `data` validated as a file's top-level
    object (entity lists and origin/environment get their own labels)."""
    loc = tuple(error["loc"])
    index = loc[1] if len(loc) >= 2 and isinstance(loc[1], int) else None
    if loc and loc[0] in ENTITY_LISTS and index is not None:
        if len(loc) > 2 and loc[2] in _TAGS.get(str(loc[0]), ()):
            loc = (*loc[:2], *loc[3:])  # the discriminator's tag
        label, start = entity_label(data, str(loc[0]), index), 2
    elif loc and loc[0] in ("origin", "environment"):
        label, start = entity_label(data, str(loc[0])), 1
    else:
        label, start = top, 0
    kind, ctx = error["type"], error.get("ctx", {})
    if kind == "missing" and len(loc) - start >= 2 and loc[-1] in ("x", "y"):
        loc = loc[:-1]  # a point without x or y: the point is the problem
        error = {**error, "type": "model_type", "ctx": {"class_name": "PointEntity"},
                 "input": _at(data, loc)}
    tag = _at(data, (*loc, "type"))
    if kind == "union_tag_not_found" or (kind == "union_tag_invalid" and tag is None):
        return f"{label}: type is required"
    if kind == "union_tag_invalid":
        options = ", ".join(_TAGS.get(str(loc[0]), ()))
        return f"{label}: type must be one of {options}; got {show(tag)}"
    rest = loc[start:]
    if kind == "entity_field":
        rest = (*rest, *str(ctx["field"]).split("."))
    field = _path(rest)
    reason = _reason(error, field)
    return f"{label}: {field} {reason}" if field else f"{label}: {reason}"


def _at(data: Any, loc: tuple[int | str, ...]) -> Any:
    for part in loc:
        try:
            data = data[part]
        except (KeyError, IndexError, TypeError):
            return None
    return data
