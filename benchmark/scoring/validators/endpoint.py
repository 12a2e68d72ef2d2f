"""A check endpoint: its parameters, how they are validated, and how it is evaluated."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from pydantic import BaseModel, ConfigDict, ValidationError, create_model

from benchmark.scoring.validators._errors import CheckDefinitionError
from benchmark.scoring.validators.context import CheckContext
from benchmark.scoring.validators.params import ENTITY_KINDS, ParamSpec, show
from emulator.scenario import Scenario

__all__ = [
    "ENDPOINT_KINDS",
    "IGNORED_PARAMETERS",
    "Endpoint",
    "Outcome",
    "Params",
    "Runner",
    "Validator",
    "all_of",
    "check_entities",
    "different",
    "ordered",
    "params_model",
    "target_kind",
]

ENDPOINT_KINDS = ("state", "history", "targets")
IGNORED_PARAMETERS = frozenset({"session_id", "since_timestamp"})
"""Accepted by every endpoint and ignored: the window is the task's own time window."""

Params = Mapping[str, Any]
Validator = Callable[[Params, "Scenario | None", str], None]
Runner = Callable[[CheckContext, Params], "Outcome"]


@dataclass(frozen=True, slots=True)
class Outcome:
    """What an endpoint measured: its boolean result and the measured value."""

    result: bool
    value: object


@dataclass(frozen=True, slots=True)
class Endpoint:
    """One check endpoint.

    kind: "state" (the instant t1), "history" (events and trajectory in the window) or
    "targets" (reach, coverage and progress in the window). validate runs cross-parameter
    checks after coercion; ignored names parameters accepted for compatibility and dropped.
    """

    name: str
    kind: str
    description: str
    params: tuple[ParamSpec, ...]
    run: Runner
    validate: Validator | None = None
    ignored: frozenset[str] = frozenset()

    def __post_init__(self) -> None:
        if self.kind not in ENDPOINT_KINDS:
            raise ValueError(f"endpoint {self.name}: kind must be one of {ENDPOINT_KINDS}")

    def normalise(self, raw: object, scenario: Scenario | None, path: str) -> Params:
        """Coerced parameters with defaults filled; raises CheckDefinitionError."""
        if raw is None:
            raw = {}
        if not isinstance(raw, Mapping):
            raise CheckDefinitionError(f"{path}: must be an object, got {show(raw)}")
        names = {p.name for p in self.params}
        for key in raw:
            if not isinstance(key, str):
                raise CheckDefinitionError(f"{path}: parameter names must be strings, got "
                                           f"{show(key)}")
            if key not in names and key not in IGNORED_PARAMETERS and key not in self.ignored:
                known = ", ".join(sorted(names)) or "none"
                raise CheckDefinitionError(
                    f"{path}.{key}: unknown parameter for {self.name} (parameters: {known})")
        given = {k: v for k, v in raw.items() if k in names and v is not None}
        try:
            model = params_model(self).model_validate(given)
        except ValidationError as error:
            first = error.errors(include_url=False)[0]
            name = str(first["loc"][0])
            if first["type"] == "missing" and len(first["loc"]) == 1:
                raise CheckDefinitionError(f"{path}.{name}: is required by {self.name}") from None
            spec = next(p for p in self.params if p.name == name)
            problem = spec.problem(first, given.get(name))
            raise CheckDefinitionError(f"{path}.{name}{problem}") from None
        params = MappingProxyType(model.__dict__)  # every parameter, in the specs' order
        check_entities(self, params, scenario, path)
        return params

    def params_schema(self) -> dict[str, Any]:
        """The JSON Schema of the endpoint's parameters (what `normalise` accepts)."""
        return params_model(self).model_json_schema()

    def to_json(self) -> dict[str, Any]:
        """A description of the endpoint for listings."""
        return {"name": self.name, "kind": self.kind, "description": self.description,
                "parameters": [p.to_json() for p in self.params]}


_MODELS: dict[int, tuple[Endpoint, type[BaseModel]]] = {}


def params_model(endpoint: Endpoint) -> type[BaseModel]:
    """The pydantic model of an endpoint's parameters, built from its specs on first use
    (cached by identity: the cache holds the endpoint, so its id is not reused)."""
    cached = _MODELS.get(id(endpoint))
    if cached is not None and cached[0] is endpoint:
        return cached[1]
    model: type[BaseModel] = create_model(  # type: ignore[call-overload]
        f"{endpoint.name}_parameters", __config__=ConfigDict(extra="ignore"),
        __doc__=endpoint.description, **{p.name: p.field() for p in endpoint.params})
    _MODELS[id(endpoint)] = (endpoint, model)
    return model


def check_entities(endpoint: Endpoint, params: Params, scenario: Scenario | None,
                   path: str) -> None:
    """Cross-parameter checks, and with a scenario, that every referenced id exists."""
    if scenario is not None:
        drones = {v.id for v in scenario.vehicles}
        for spec in endpoint.params:
            value = params.get(spec.name)
            if value is None:
                continue
            where = f"{path}.{spec.name}"
            if spec.kind in ENTITY_KINDS:
                _check_id(spec.kind, value, drones, scenario, where)
            elif spec.kind == "drones":
                for k, ident in enumerate(value):
                    _check_id("drone", ident, drones, scenario, f"{where}[{k}]")
    if endpoint.validate is not None:
        endpoint.validate(params, scenario, path)


def _check_id(kind: str, ident: str, drones: set[str], scenario: Scenario, where: str) -> None:
    if kind == "drone":
        known = ident in drones
    elif kind == "target":
        known = any(t.id == ident for t in scenario.world.targets)
    else:
        known = any(o.id == ident for o in scenario.world.obstacles)
    if not known:
        raise CheckDefinitionError(
            f"{where}: {kind} {ident!r} is not in scenario {scenario.name!r}")


def ordered(low: str, high: str) -> Validator:
    """Parameters low and high, when both given, must satisfy low <= high."""
    def validate(params: Params, scenario: Scenario | None, path: str) -> None:
        lo, hi = params.get(low), params.get(high)
        if lo is not None and hi is not None and hi < lo:
            raise CheckDefinitionError(
                f"{path}.{high}: must be >= {low} ({lo:g}), got {hi:g}")
    return validate


def different(first: str, second: str) -> Validator:
    """Parameters first and second must name different entities."""
    def validate(params: Params, scenario: Scenario | None, path: str) -> None:
        if params.get(first) is not None and params.get(first) == params.get(second):
            raise CheckDefinitionError(
                f"{path}.{second}: must differ from {first}, both are {params[first]!r}")
    return validate


def target_kind(name: str, kind: str) -> Validator:
    """With a scenario, the target named by parameter name must be of the given kind."""
    def validate(params: Params, scenario: Scenario | None, path: str) -> None:
        ident = params.get(name)
        if scenario is None or ident is None:
            return
        found = [t for t in scenario.world.targets if t.id == ident]
        if found and found[0].kind != kind:
            raise CheckDefinitionError(
                f"{path}.{name}: target {ident!r} is of kind {found[0].kind!r}, "
                f"this check needs a {kind!r} target")
    return validate


def all_of(*validators: Validator) -> Validator:
    """Run several validators in order."""
    def validate(params: Params, scenario: Scenario | None, path: str) -> None:
        for check in validators:
            check(params, scenario, path)
    return validate
