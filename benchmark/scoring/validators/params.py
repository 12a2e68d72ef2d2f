"""Parameter specifications of check endpoints, with coercion of JSON and query-string values.

Values arrive as the reference stores them: numbers may be floats for integer parameters
(12.0), numbers may be strings ("12.0"), booleans may be "true"/"false". Every problem raises
:class:`CheckDefinitionError` whose message starts with the parameter's path.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from benchmark.scoring.validators._errors import CheckDefinitionError

__all__ = [
    "ENTITY_KINDS",
    "REQUIRED",
    "ParamSpec",
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
_TRUE = ("true", "1", "yes", "on")
_FALSE = ("false", "0", "no", "off")


def show(value: object) -> str:
    """A value as it reads in JSON, shortened for messages."""
    try:
        shown = json.dumps(value)
    except (TypeError, ValueError):
        shown = repr(value)
    return shown if len(shown) <= 60 else shown[:57] + "..."


@dataclass(frozen=True, slots=True)
class ParamSpec:
    """One parameter: its name, type (kind), default, inclusive range or choices.

    kind is one of float, int, bool, str, choice, drone, target, obstacle, drones, point.
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

    def coerce(self, raw: object, path: str) -> Any:
        """The normalised value of raw (not None), or CheckDefinitionError naming path."""
        if self.kind == "float":
            return self._in_range(_to_float(raw, path), path)
        if self.kind == "int":
            return self._in_range(_to_int(raw, path), path)
        if self.kind == "bool":
            return _to_bool(raw, path)
        if self.kind in ("str", *ENTITY_KINDS):
            entity_id = self.kind in ENTITY_KINDS
            return _to_text(raw, path, "an id (a non-empty string)" if entity_id
                            else "a non-empty string")
        if self.kind == "choice":
            value = _to_text(raw, path, "a non-empty string")
            if value not in self.choices:
                raise CheckDefinitionError(
                    f"{path}: must be one of {', '.join(self.choices)}; got {show(raw)}")
            return value
        if self.kind == "drones":
            return _to_id_list(raw, path)
        if self.kind == "point":
            return _to_point(raw, path)
        raise AssertionError(f"unknown parameter kind {self.kind!r}")

    def _in_range(self, value: float, path: str) -> Any:
        if self.minimum is not None and value < self.minimum:
            raise CheckDefinitionError(f"{path}: must be >= {self.minimum:g}, got {value:g}")
        if self.maximum is not None and value > self.maximum:
            raise CheckDefinitionError(f"{path}: must be <= {self.maximum:g}, got {value:g}")
        return value

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


def _to_float(raw: object, path: str) -> float:
    if isinstance(raw, bool):
        raise CheckDefinitionError(f"{path}: must be a number, got {show(raw)}")
    if isinstance(raw, int | float):
        value = float(raw)
    elif isinstance(raw, str):
        try:
            value = float(raw.strip())
        except ValueError:
            raise CheckDefinitionError(f"{path}: must be a number, got {show(raw)}") from None
    else:
        raise CheckDefinitionError(f"{path}: must be a number, got {show(raw)}")
    if not math.isfinite(value):
        raise CheckDefinitionError(f"{path}: must be a finite number, got {show(raw)}")
    return value


def _to_int(raw: object, path: str) -> int:
    if isinstance(raw, int) and not isinstance(raw, bool):
        return raw
    value = _to_float(raw, path)
    if not value.is_integer():
        raise CheckDefinitionError(f"{path}: must be a whole number, got {show(raw)}")
    return int(value)


def _to_bool(raw: object, path: str) -> bool:
    if isinstance(raw, bool):
        return raw
    if isinstance(raw, int) and raw in (0, 1):
        return bool(raw)
    if isinstance(raw, str) and raw.strip().lower() in _TRUE + _FALSE:
        return raw.strip().lower() in _TRUE
    raise CheckDefinitionError(f"{path}: must be true or false, got {show(raw)}")


def _to_text(raw: object, path: str, what: str) -> str:
    if not isinstance(raw, str) or not raw.strip():
        raise CheckDefinitionError(f"{path}: must be {what}, got {show(raw)}")
    return raw


def _to_id_list(raw: object, path: str) -> tuple[str, ...]:
    if isinstance(raw, str) or not isinstance(raw, list | tuple):
        raise CheckDefinitionError(f"{path}: must be a list of drone ids, got {show(raw)}")
    ids = tuple(_to_text(item, f"{path}[{k}]", "an id (a non-empty string)")
                for k, item in enumerate(raw))
    if len(ids) < 2:
        raise CheckDefinitionError(f"{path}: must list at least 2 drones, got {len(ids)}")
    seen: set[str] = set()
    for k, ident in enumerate(ids):
        if ident in seen:
            raise CheckDefinitionError(f"{path}[{k}]: drone {ident!r} is listed twice")
        seen.add(ident)
    return ids


def _to_point(raw: object, path: str) -> Mapping[str, float]:
    data = raw
    if isinstance(raw, str):
        try:
            data = json.loads(raw)
        except json.JSONDecodeError:
            raise CheckDefinitionError(
                f"{path}: must be an object {{\"x\", \"y\"[, \"z\"]}} or its JSON text, "
                f"got {show(raw)}") from None
    if not isinstance(data, Mapping) or data.get("x") is None or data.get("y") is None:
        raise CheckDefinitionError(
            f"{path}: must be an object {{\"x\", \"y\"[, \"z\"]}} or its JSON text, "
            f"got {show(raw)}")
    if extra := sorted(str(k) for k in data if k not in ("x", "y", "z")):
        raise CheckDefinitionError(f"{path}: unknown key(s) {', '.join(extra)}; use x, y, z")
    point = {axis: _to_float(data[axis], f"{path}.{axis}") for axis in ("x", "y")}
    if data.get("z") is not None:
        point["z"] = _to_float(data["z"], f"{path}.z")
    return MappingProxyType(point)


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
