"""JSON Schemas from Python signatures, and argument validation against them.

A tool is a typed function; its parameters (after the bound context) become a strict object
schema (`additionalProperties: false`, every parameter without a default required), and the
docstring's ``Args:`` section gives each property its description. Validation returns a list
of readable problems rather than raising, so a model gets something it can act on.
"""

from __future__ import annotations

import inspect
import types
import typing
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import docstring_parser

from llm_tools.input_limits import MAX_ITEMS, InputError, check_bounds, check_text, preview

__all__ = ["describe", "schema_for", "validate"]

MAX_LISTED = 5  # unknown argument names echoed back at most


def describe(fn: Callable[..., Any]) -> tuple[str, dict[str, str]]:
    """(summary, {parameter: description}) from a Google-style docstring (read by
    docstring-parser); the summary is every paragraph before the sections, on one line."""
    doc = docstring_parser.parse(inspect.getdoc(fn) or "",
                                 style=docstring_parser.DocstringStyle.GOOGLE)
    summary = " ".join(part for part in (doc.short_description, doc.long_description) if part)
    params = {p.arg_name: " ".join((p.description or "").split()) for p in doc.params}
    return " ".join(summary.split()), params


def _type_schema(annotation: Any) -> dict[str, Any]:
    origin = typing.get_origin(annotation)
    args = typing.get_args(annotation)
    if annotation is str:
        return {"type": "string"}
    if annotation is bool:
        return {"type": "boolean"}
    if annotation is int:
        return {"type": "integer"}
    if annotation is float:
        return {"type": "number"}
    if origin is typing.Literal:
        return {"type": "string", "enum": list(args)}
    if origin in (list, Sequence, tuple) and args:
        return {"type": "array", "items": _type_schema(args[0])}
    if origin in (typing.Union, types.UnionType):
        real = [a for a in args if a is not type(None)]
        if len(real) == 1:
            return _type_schema(real[0])
    raise TypeError(f"no JSON Schema for annotation {annotation!r}")


def schema_for(fn: Callable[..., Any], *, skip: int = 1) -> dict[str, Any]:
    """The strict object schema of fn's parameters after the first `skip` (bound) ones."""
    hints = typing.get_type_hints(fn)
    _, docs = describe(fn)
    properties: dict[str, Any] = {}
    required: list[str] = []
    for param in list(inspect.signature(fn).parameters.values())[skip:]:
        prop = _type_schema(hints[param.name])
        if param.name in docs:
            prop["description"] = docs[param.name]
        if param.default is inspect.Parameter.empty:
            required.append(param.name)
        else:
            prop["default"] = param.default
        properties[param.name] = prop
    return {"type": "object", "properties": properties, "required": required,
            "additionalProperties": False}


def _check(value: Any, schema: Mapping[str, Any], where: str, problems: list[str]) -> Any:
    kind = schema.get("type")
    if kind == "string":
        if not isinstance(value, str):
            problems.append(f"{where} must be a string, got {preview(value)}")
        elif "enum" in schema and value not in schema["enum"]:
            problems.append(f"{where} must be one of {schema['enum']}, got {preview(value)}")
        else:
            try:
                check_text(value, where)
            except InputError as error:
                problems.append(str(error))
        return value
    if kind == "boolean":
        if not isinstance(value, bool):
            problems.append(f"{where} must be true or false, got {preview(value)}")
        return value
    if kind in ("number", "integer"):
        if isinstance(value, bool) or not isinstance(value, int | float):
            problems.append(f"{where} must be a number, got {preview(value)}")
            return value
        try:
            check_bounds(value, where)
        except InputError as error:
            problems.append(str(error))
            return value
        if kind == "integer":
            if float(value) != int(value):
                problems.append(f"{where} must be a whole number, got {value}")
            return int(value)
        return float(value)
    if kind == "array":
        if not isinstance(value, list):
            problems.append(f"{where} must be a list, got {preview(value)}")
            return value
        most = min(MAX_ITEMS, schema.get("maxItems", MAX_ITEMS))
        if len(value) > most:
            problems.append(f"{where} has {len(value)} items; the limit is {most}")
            return value
        if len(value) < schema.get("minItems", 0):
            problems.append(f"{where} needs at least {schema['minItems']} item(s), "
                            f"got {len(value)}")
            return value
        return [_check(v, schema["items"], f"{where}[{i}]", problems)
                for i, v in enumerate(value)]
    return value


def validate(arguments: Any, schema: Mapping[str, Any]) -> tuple[dict[str, Any], list[str]]:
    """(coerced arguments, problems) for an object schema from `schema_for`. Never raises:
    any value, however large, deep or odd, gives problems a caller can read."""
    if arguments is None:
        arguments = {}
    if not isinstance(arguments, Mapping):
        return {}, [f"arguments must be a JSON object, got {preview(arguments)}"]
    props = schema["properties"]
    extra = [k for k in arguments if k not in props]
    problems: list[str] = []
    if extra:
        shown = ", ".join(preview(k) for k in extra[:MAX_LISTED])
        more = f" and {len(extra) - MAX_LISTED} more" if len(extra) > MAX_LISTED else ""
        problems.append(f"unknown argument(s) {shown}{more}; expected "
                        f"{', '.join(props) or 'none'}")
    missing = [k for k in schema["required"] if k not in arguments]
    if missing:
        problems.append(f"missing required argument(s) {', '.join(map(repr, missing))}")
    values = {k: _check(v, props[k], k, problems) for k, v in arguments.items() if k in props}
    if len(problems) > MAX_LISTED:
        problems[MAX_LISTED:] = [f"and {len(problems) - MAX_LISTED} more problems"]
    return values, problems
