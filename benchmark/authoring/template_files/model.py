"""The template file format (``mavswarm.template/1``): one JSON file per task template. Its
JSON Schema (`template.schema.json` beside this module) is generated from these models.

Example::

    {"format": "mavswarm.template/1", "id": "takeoff_hold", "category": "basic_operations",
     "difficulty": "easy",
     "entities": [{"group": "drone_1", "kind": "drone"}],
     "values": [{"name": "alt", "kind": "int", "min": 8, "max": 25}],
     "phrasings": ["Take off with {drone_1_name} to {alt} m and hold position there."],
     "checks": {"logic": "and", "checks": [{"endpoint": "drone_altitude", "parameters":
                {"drone_id": "{drone_1_id}", "expected_altitude": "{alt}"}}]},
     "budget": {"steps": 1}}

Entities are drawn first, in the order listed, then the named values, in order, from the
task's seeded generator; phrasings, checks and the optional hand plan are then filled in
(`benchmark.authoring.template_files.placeholders`, which also accepts the reference's vocabulary).
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator, model_validator

__all__ = ["FORMAT", "Budget", "EntityGroup", "TemplateFile", "ValueSpec", "json_schema"]

FORMAT: Literal["mavswarm.template/1"] = "mavswarm.template/1"
CATEGORIES = ("basic_operations", "navigation", "search", "multi_drone_coordination",
              "delivery", "communication", "battery_management", "target_tracking",
              "resilience")  # benchmark.authoring.templates.base.CATEGORIES (kept equal by a test)
ENTITY_KINDS = ("drone", "area_target", "point_target", "moving_target", "station",
                "inspectable", "target", "obstacle")
FAMILIES = ("area_search", "area_assignment_and_patrol", "target_assignment",
            "target_tracking", "resilience")
LEVELS = ("easy", "moderate", "intermediate", "hard", "extreme")


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class EntityGroup(_Strict):
    """A group of the session's entities: ``{<group>_id}`` and ``{<group>_name}`` name it."""

    group: str = Field(pattern=r"^[a-z][a-z0-9]*(_[0-9]+)?$",
                       description="placeholder stem, e.g. drone_1 (gives {drone_1_id} and "
                                   "{drone_1_name}); the reference names drone, target, "
                                   "obstacle and drone_1 ... target_6")
    kind: Literal["drone", "area_target", "point_target", "moving_target", "station",
                  "inspectable", "target", "obstacle"] = Field(
        description="which entities it is drawn from (inspectable: fixed point targets, then "
                    "area targets; target: any target)")


class ValueSpec(_Strict):
    """A named random value drawn once per task (sticky): ``{name}`` everywhere."""

    name: str = Field(pattern=r"^[a-z][a-z0-9_]*$")
    kind: Literal["int", "float", "point", "choice", "hook"] = Field(
        description="int: randint(min, max) (with step: randrange(min, max + 1, step)); float: "
                    "uniform rounded to decimals; point: a free spot (x, y) in region; choice: "
                    "one of options; hook: what a named Python function returns")
    call: str | None = Field(
        default=None, pattern=r"^[A-Za-z_][\w.]*:[A-Za-z_]\w*$",
        description="hook: module:function called as function(view, rng, values, entities); "
                    "it returns a dict of named values (merged), for what a file cannot say")
    options: list[str | int | float] = Field(default_factory=list,
                                             description="choice: the values drawn from")
    min: float | None = None
    max: float | None = None
    step: int | None = Field(default=None, ge=1)
    decimals: int = Field(default=1, ge=0, le=6)
    region: tuple[float, float, float, float] | None = Field(
        default=None, description="point: the region as fractions of the map (x0, y0, x1, "
                                  "y1); default the map less a 30 m margin")
    clearance_m: float = Field(default=15.0, ge=0.0,
                               description="point: least distance to every obstacle")

    @model_validator(mode="after")
    def _range(self) -> ValueSpec:
        if self.kind == "hook" and self.call is None:
            raise ValueError(f"value {self.name!r}: a hook needs call (module:function)")
        if self.kind == "choice" and not self.options:
            raise ValueError(f"value {self.name!r}: a choice needs options")
        if self.kind in ("int", "float"):
            if self.min is None or self.max is None:
                raise ValueError(f"value {self.name!r}: an {self.kind} needs min and max")
            if self.max < self.min:
                raise ValueError(f"value {self.name!r}: max {self.max:g} < min {self.min:g}")
        return self


class Budget(_Strict):
    """What the budget (tool calls, simulated seconds) is computed from, as for built-ins."""

    steps: int | str = Field(default=4, description="primitive calls of a plan, or a value's "
                                                    "placeholder")
    flight_m: float | str = Field(default=0.0, description="rough flight distance (m), or a "
                                                           "value's placeholder")
    flight_diagonals: float = Field(default=0.0, ge=0.0,
                                    description="flight distance in map diagonals (added)")
    hover_s: float | str = Field(default=0.0, description="seconds, or a value's placeholder "
                                                          "such as {hover}")


class TemplateFile(_Strict):
    """One task template as a file."""

    format: Literal["mavswarm.template/1"] = FORMAT
    id: str = Field(pattern=r"^[a-z][a-z0-9_]*$")
    category: str = Field(description=f"one of {', '.join(CATEGORIES)}")
    difficulty: Literal["easy", "medium", "hard"] = "medium"
    description: str = ""
    families: list[str] = Field(default_factory=list,
                                description="families it suits (empty: every family)")
    levels: list[str] = Field(default_factory=list,
                              description="levels it suits (empty: every level)")
    entities: list[EntityGroup] = Field(default_factory=list)
    distinct: bool | Literal["when_enough"] = Field(
        default=True,
        description="groups of one kind get distinct entities (when_enough: distinct when the "
                    "session has enough of that kind, else each group draws any, as the "
                    "reference does)")
    values: list[ValueSpec] = Field(default_factory=list)
    phrasings: list[str] = Field(min_length=1,
                                 description="the first is given to agents, others are aliases")
    checks: Any = Field(description="a check tree over the validator endpoints, placeholders "
                                    "in strings")
    plan: list[list[dict[str, Any]]] | None = Field(
        default=None, description="optional hand plan (phases of oracle operations)")
    budget: Budget = Field(default_factory=Budget)
    faults: dict[str, Any] | None = Field(
        default=None, description="hidden faults (benchmark.authoring.task_faults), "
                                  "placeholders in strings and keys")

    @field_validator("category")
    @classmethod
    def _category(cls, value: str) -> str:
        if value not in CATEGORIES:
            raise ValueError(f"{value!r} is not one of {', '.join(CATEGORIES)}")
        return value

    @field_validator("families", "levels")
    @classmethod
    def _names(cls, value: list[str], info: ValidationInfo) -> list[str]:
        known = FAMILIES if info.field_name == "families" else LEVELS
        for name in value:
            if name not in known:
                raise ValueError(f"{name!r} is not one of {', '.join(known)}")
        return value

    @field_validator("entities", "values")
    @classmethod
    def _unique(cls, value: list[Any], info: ValidationInfo) -> list[Any]:
        names = [getattr(v, "group", None) or getattr(v, "name", None) for v in value]
        if len(set(names)) != len(names):
            raise ValueError(f"two {info.field_name} share a name")
        return value


def json_schema() -> dict[str, Any]:
    """The JSON Schema of a template file."""
    schema = TemplateFile.model_json_schema()
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["$id"] = "https://mavswarm.dev/schemas/template-1.json"
    return schema
