"""Parameter specifications of check endpoints and the pydantic types that coerce their JSON
and query-string values.

Values arrive as the reference stores them: numbers may be floats for integer parameters
(12.0), numbers may be strings ("12.0"), booleans may be "true"/"false" (pydantic's lax mode
reads all of these; JSON booleans are not numbers). Each endpoint validates its parameters
with one pydantic model built from its specs (`benchmark.scoring.validators.endpoint`), and every
problem becomes a :class:`CheckDefinitionError` whose message starts with the parameter's path.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Annotated, Any, Literal

from pydantic import (
    AfterValidator,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    GetPydanticSchema,
)
from pydantic_core import ErrorDetails, PydanticCustomError, core_schema

__all__ = [
    "ENTITY_KINDS",
    "REQUIRED",
    "ParamSpec",
    "PointParam",
    "drone_list",
    "entity",
    "flag",
    "integer",
    "number",
    "point",
    "show",
    "text",
]


class _Required:
    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED: Any = _Required()
"""Default of a parameter that must be given."""

ENTITY_KINDS = ("drone", "target", "obstacle")


def show(value: object) -> str:
    """A value as it reads in JSON, shortened for messages."""
    try:
        shown = json.dumps(value)
    except (TypeError, ValueError):
        shown = repr(value)
    return shown if len(shown) <= 60 else shown[:57] + "..."


def _not_a_bool(raw: Any) -> Any:
    """JSON booleans are not numbers here (pydantic's lax mode would read true as 1)."""
    if isinstance(raw, bool):
        raise PydanticCustomError("number_type", "must be a number")
    return raw


def _whole(raw: Any) -> Any:
    """An integer may be written as any number text ("12.0", "1e1"): read it as a float,
    which pydantic then takes only if it is whole."""
    if isinstance(raw, str):
        try:
            return float(raw)
        except ValueError:
            return raw
    return _not_a_bool(raw)


def _json_text(raw: Any) -> Any:
    """A point may come as the JSON text of its object (query strings)."""
    if isinstance(raw, str):
        try:
            return json.loads(raw)
        except json.JSONDecodeError:
            raise PydanticCustomError("point_type", "not an object") from None
    return raw


def _distinct(ids: tuple[str, ...]) -> tuple[str, ...]:
    seen: set[str] = set()
    for k, ident in enumerate(ids):
        if ident in seen:
            raise PydanticCustomError("listed_twice", "drone {ident!r} is listed twice",
                                      {"index": k, "ident": ident})
        seen.add(ident)
    return ids


def _non_empty(kind: str, message: str) -> GetPydanticSchema:
    return GetPydanticSchema(lambda tp, handler: core_schema.custom_error_schema(
        handler(tp), custom_error_type=kind, custom_error_message=message))


Number = Annotated[float, BeforeValidator(_not_a_bool), Field(allow_inf_nan=False)]
Text = Annotated[str, Field(strict=True, pattern=r"\S"),
                 _non_empty("non_empty_string", "must be a non-empty string")]
EntityId = Annotated[str, Field(strict=True, pattern=r"\S"),
                     _non_empty("entity_id", "must be an id (a non-empty string)")]


class PointParam(BaseModel):
    """A point {x, y[, z]} in local metres (or the JSON text of one)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    x: Number
    y: Number
    z: Number | None = None

    def as_mapping(self) -> Mapping[str, float]:
        point = {"x": self.x, "y": self.y}
        if self.z is not None:
            point["z"] = self.z
        return MappingProxyType(point)


@dataclass(frozen=True, slots=True)
class ParamSpec:
    """One parameter: its name, type (kind), default, inclusive range or choices.

    kind is one of float, int, bool, str, choice, drone, target, obstacle, drones, point;
    `annotation` is the pydantic type that validates and coerces it (`benchmark.scoring.validators
    .endpoint` builds one model per endpoint from its parameters).
    """

    name: str
    kind: str
    default: Any = REQUIRED
    minimum: float | None = None
    maximum: float | None = None
    choices: tuple[str, ...] = ()
    description: str = ""

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def annotation(self) -> Any:
        """The pydantic type of the parameter's value (a default of None makes it optional)."""
        bounds = Field(ge=self.minimum, le=self.maximum)
        kinds: dict[str, Any] = {
            "float": Annotated[float, Field(allow_inf_nan=False), bounds,
                               BeforeValidator(_not_a_bool)],
            "int": Annotated[int, bounds, BeforeValidator(_whole)],
            "bool": bool,
            "str": Text,
            "choice": Literal[self.choices] if self.choices else Text,
            "drones": Annotated[tuple[EntityId, ...], Field(min_length=2),
                                AfterValidator(_distinct)],
            "point": Annotated[PointParam, BeforeValidator(_json_text),
                               AfterValidator(PointParam.as_mapping)],
        }
        value = kinds.get(self.kind, EntityId if self.kind in ENTITY_KINDS else None)
        if value is None:
            raise AssertionError(f"unknown parameter kind {self.kind!r}")
        return value | None if self.default is None else value

    def field(self) -> tuple[Any, Any]:
        """(type, FieldInfo) for pydantic.create_model."""
        default = ... if self.required else self.default
        return self.annotation(), Field(default, description=self.description or None)

    def problem(self, error: ErrorDetails, value: object) -> str:
        """Where in this parameter's value and what is wrong (`.x: must be a number, got
        "a"`, `[2]: drone 'd1' is listed twice`, `: must be >= 0, got -1`), from a pydantic
        error about it."""
        kind, got, ctx = error["type"], show(error["input"]), error.get("ctx", {})
        rest = error["loc"][1:]
        where = "".join(f"[{part}]" if isinstance(part, int) else f".{part}" for part in rest)
        if self.kind == "point" and (kind in ("point_type", "model_type", "missing")
                                     or (kind == "float_type" and error["input"] is None)):
            return (": must be an object {\"x\", \"y\"[, \"z\"]} or its JSON text, got "
                    f"{show(value)}")
        if self.kind == "point" and kind == "extra_forbidden":
            return f": unknown key(s) {rest[-1]}; use x, y, z"
        if kind == "listed_twice":
            return f"[{ctx['index']}]: drone {ctx['ident']!r} is listed twice"
        return f"{where}: {self._reason(error, kind, got, ctx)}"

    def _reason(self, error: ErrorDetails, kind: str, got: str, ctx: dict[str, Any]) -> str:
        if kind in ("number_type", "float_type", "float_parsing", "int_parsing", "int_type"):
            return f"must be a number, got {got}"
        if kind == "int_from_float":
            return f"must be a whole number, got {got}"
        if kind == "finite_number":
            return f"must be a finite number, got {got}"
        if kind in ("greater_than_equal", "less_than_equal"):
            sign, limit = (">=", ctx["ge"]) if kind == "greater_than_equal" else ("<=", ctx["le"])
            value = error["input"]
            shown = f"{float(value):g}" if isinstance(value, int | float | str) else got
            return f"must be {sign} {limit:g}, got {shown}"
        if kind in ("bool_type", "bool_parsing"):
            return f"must be true or false, got {got}"
        if kind == "literal_error":
            return f"must be one of {', '.join(self.choices)}; got {got}"
        if kind == "too_short" and self.kind == "drones":
            return f"must list at least 2 drones, got {len(error['input'])}"
        if kind in ("tuple_type", "list_type") and self.kind == "drones":
            return f"must be a list of drone ids, got {got}"
        if kind in ("non_empty_string", "entity_id"):
            return f"{error['msg']}, got {got}"
        return f"is invalid: {error['msg']}"

    def to_json(self) -> dict[str, Any]:
        """A description of the parameter for listings."""
        out: dict[str, Any] = {"name": self.name, "type": self.kind, "required": self.required}
        if not self.required:
            out["default"] = self.default
        if self.minimum is not None:
            out["minimum"] = self.minimum
        if self.maximum is not None:
            out["maximum"] = self.maximum
        if self.choices:
            out["choices"] = list(self.choices)
        if self.description:
            out["description"] = self.description
        return out


def number(name: str, default: Any = REQUIRED, *, minimum: float | None = None,
           maximum: float | None = None, description: str = "") -> ParamSpec:
    return ParamSpec(name, "float", default, minimum, maximum, description=description)


def integer(name: str, default: Any = REQUIRED, *, minimum: float | None = None,
            maximum: float | None = None, description: str = "") -> ParamSpec:
    return ParamSpec(name, "int", default, minimum, maximum, description=description)


def flag(name: str, default: Any = REQUIRED, description: str = "") -> ParamSpec:
    return ParamSpec(name, "bool", default, description=description)


def text(name: str, default: Any = REQUIRED, *, choices: tuple[str, ...] = (),
         description: str = "") -> ParamSpec:
    return ParamSpec(name, "choice" if choices else "str", default, choices=choices,
                     description=description)


def entity(name: str, kind: str, default: Any = REQUIRED, description: str = "") -> ParamSpec:
    if kind not in ENTITY_KINDS:
        raise ValueError(f"entity kind must be one of {ENTITY_KINDS}, got {kind!r}")
    return ParamSpec(name, kind, default, description=description)


def drone_list(name: str, description: str = "") -> ParamSpec:
    return ParamSpec(name, "drones", description=description)


def point(name: str, default: Any = REQUIRED, description: str = "") -> ParamSpec:
    return ParamSpec(name, "point", default, description=description)
