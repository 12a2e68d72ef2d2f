"""A pydantic model of a tool's arguments from its Python signature, the JSON Schema
generated from it, and argument validation with it.

A tool is a typed function; its parameters (after the bound context) become a model that
refuses unknown arguments (its schema: `additionalProperties: false`, every parameter without
a default required), and the docstring's ``Args:`` section (read by docstring-parser) gives
each field its description. Validation returns a list of readable problems rather than
raising, so a model gets something it can act on.
"""

from __future__ import annotations

import copy
import functools
import inspect
import types
import typing
from collections.abc import Callable, Mapping, Sequence
from typing import Annotated, Any

import docstring_parser
from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    Strict,
    ValidationError,
    create_model,
)
from pydantic.json_schema import GenerateJsonSchema
from pydantic_core import ErrorDetails, PydanticCustomError

from llm_tools.input_limits import MAX_ITEMS, InputError, check_bounds, check_text, preview

__all__ = ["arguments_model", "describe", "model_schema", "schema_for", "validate"]

MAX_LISTED = 5  # unknown argument names echoed back at most


def describe(fn: Callable[..., Any]) -> tuple[str, dict[str, str]]:
    """(summary, {parameter: description}) from a Google-style docstring (read by
    docstring-parser); the summary is every paragraph before the sections, on one line."""
    doc = docstring_parser.parse(inspect.getdoc(fn) or "",
                                 style=docstring_parser.DocstringStyle.GOOGLE)
    summary = " ".join(part for part in (doc.short_description, doc.long_description) if part)
    params = {p.arg_name: " ".join((p.description or "").split()) for p in doc.params}
    return " ".join(summary.split()), params


def _text(value: str) -> str:
    try:
        check_text(value, "")
    except InputError as error:
        raise PydanticCustomError("input_bound", "{problem}", {"problem": error.problem}) \
            from None
    return value


def _number(value: Any) -> Any:
    """Numbers are JSON numbers (not booleans, not text), finite and within the bounds."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise PydanticCustomError("not_a_number", "must be a number")
    try:
        check_bounds(value, "")
    except InputError as error:
        raise PydanticCustomError("input_bound", "{problem}", {"problem": error.problem}) \
            from None
    return value


def _string(value: Any) -> Any:
    if not isinstance(value, str):
        raise PydanticCustomError("string_type", "must be a string")
    return value


def _items(value: list[Any]) -> list[Any]:
    if len(value) > MAX_ITEMS:
        raise PydanticCustomError("too_many_items", "{count}", {"count": len(value),
                                                                "limit": MAX_ITEMS})
    return value


def _checked(annotation: Any) -> Any:
    """The pydantic type that validates a parameter annotated `annotation` as a tool
    argument (None is refused even where the default is None: omit the argument)."""
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if annotation is str:
        return Annotated[str, Strict(), AfterValidator(_text)]
    if annotation is bool:
        return Annotated[bool, Strict()]
    if annotation in (int, float):
        return Annotated[annotation, BeforeValidator(_number)]
    if origin is typing.Literal:
        return Annotated[annotation, BeforeValidator(_string)]
    if origin in (list, Sequence, tuple) and args:
        return Annotated[list[_checked(args[0])], Strict(),  # type: ignore[misc]
                         AfterValidator(_items)]
    if origin in (typing.Union, types.UnionType):
        real = [a for a in args if a is not type(None)]
        if len(real) == 1:
            return _checked(real[0])
    raise TypeError(f"no JSON Schema for annotation {annotation!r}")


@functools.lru_cache(maxsize=512)
def arguments_model(fn: Callable[..., Any], *, skip: int = 1) -> type[BaseModel]:
    """A pydantic model of fn's parameters after the first `skip` (bound) ones: their types,
    defaults and docstring descriptions; unknown arguments are refused (built once per
    function)."""
    hints = typing.get_type_hints(fn)
    _, docs = describe(fn)
    fields: dict[str, Any] = {}
    for param in list(inspect.signature(fn).parameters.values())[skip:]:
        default = ... if param.default is inspect.Parameter.empty else param.default
        fields[param.name] = (_checked(hints[param.name]),
                              Field(default, description=docs.get(param.name)))
    name = f"{getattr(fn, '__name__', 'tool')}_arguments"
    model: type[BaseModel] = create_model(name, __config__=ConfigDict(extra="forbid"),
                                          **fields)
    return model


class _ToolSchema(GenerateJsonSchema):
    """JSON Schema as the tool surfaces publish it: no titles."""

    def field_title_should_be_set(self, schema: Any) -> bool:
        return False


def model_schema(model: type[BaseModel]) -> dict[str, Any]:
    """The strict object schema of an arguments model (`additionalProperties: false`, every
    parameter without a default required); a fresh copy each time."""
    return copy.deepcopy(_model_schema(model))


@functools.lru_cache(maxsize=512)
def _model_schema(model: type[BaseModel]) -> dict[str, Any]:
    schema = model.model_json_schema(schema_generator=_ToolSchema)
    schema.pop("title", None)
    schema.pop("description", None)
    schema.setdefault("required", [])
    return schema


def schema_for(fn: Callable[..., Any], *, skip: int = 1) -> dict[str, Any]:
    """The strict object schema of fn's parameters after the first `skip` (bound) ones."""
    return model_schema(arguments_model(fn, skip=skip))


def _where(loc: tuple[int | str, ...]) -> str:
    out = ""
    for part in loc:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


def _problem(error: ErrorDetails) -> str:
    where, kind, got = _where(tuple(error["loc"])), error["type"], preview(error["input"])
    ctx = error.get("ctx", {})
    if kind == "input_bound":
        return f"{where} {ctx['problem']}"
    if kind in ("not_a_number", "float_type", "int_type"):
        return f"{where} must be a number, got {got}"
    if kind == "int_from_float":
        return f"{where} must be a whole number, got {error['input']}"
    if kind == "string_type":
        return f"{where} must be a string, got {got}"
    if kind == "literal_error":
        options = [o.strip("'") for o in str(ctx["expected"]).replace(" or ", ", ").split(", ")]
        return f"{where} must be one of {options}, got {got}"
    if kind == "bool_type":
        return f"{where} must be true or false, got {got}"
    if kind == "list_type":
        return f"{where} must be a list, got {got}"
    if kind == "too_many_items":
        return f"{where} has {ctx['count']} items; the limit is {ctx['limit']}"
    if kind == "too_long":
        return f"{where} has {ctx['actual_length']} items; the limit is {ctx['max_length']}"
    if kind == "too_short":
        return (f"{where} needs at least {ctx['min_length']} item(s), "
                f"got {ctx['actual_length']}")
    return f"{where}: {error['msg']}"


def validate(arguments: Any, model: type[BaseModel]) -> tuple[dict[str, Any], list[str]]:
    """(arguments as the tool takes them, problems) for an arguments model. Never raises:
    any value, however large, deep or odd, gives problems a caller can read."""
    if arguments is None:
        arguments = {}
    if not isinstance(arguments, Mapping):
        return {}, [f"arguments must be a JSON object, got {preview(arguments)}"]
    try:
        parsed = model.model_validate(dict(arguments))
    except ValidationError as error:
        return {}, _problems(error.errors(include_url=False), model)
    return {k: getattr(parsed, k) for k in arguments if k in parsed.model_fields_set}, []


def _problems(errors: Sequence[ErrorDetails], model: type[BaseModel]) -> list[str]:
    """Unknown arguments and missing ones, each group in one problem, then the others."""
    extra = [e["loc"][0] for e in errors if e["type"] == "extra_forbidden"]
    missing = [str(e["loc"][0]) for e in errors if e["type"] == "missing" and len(e["loc"]) == 1]
    problems: list[str] = []
    if extra:
        shown = ", ".join(preview(k) for k in extra[:MAX_LISTED])
        more = f" and {len(extra) - MAX_LISTED} more" if len(extra) > MAX_LISTED else ""
        problems.append(f"unknown argument(s) {shown}{more}; expected "
                        f"{', '.join(model.model_fields) or 'none'}")
    if missing:
        problems.append(f"missing required argument(s) {', '.join(map(repr, missing))}")
    problems += [_problem(e) for e in errors if e["type"] not in ("extra_forbidden", "missing")
                 or (e["type"] == "missing" and len(e["loc"]) > 1)]
    if len(problems) > MAX_LISTED:
        problems[MAX_LISTED:] = [f"and {len(problems) - MAX_LISTED} more problems"]
    return problems
