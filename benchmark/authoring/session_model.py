"""The session file format (``mavswarm.session/1``) as pydantic models; its JSON Schema
(`session.schema.json` beside this module) is generated from `SessionFile`.

A session file is a scenario file (`emulator.scenario_model.ScenarioFile`: drones, targets,
obstacles, environment, origin, safety margin) with the session's identity and its tasks.
`SessionHeader` is what loading checks of the whole file; each task is checked on its own
(`TaskFile`), so that one bad task is kept with its error and the others still load.

``python -m benchmark.authoring.session_model`` rewrites `session.schema.json` from the models.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any, ForwardRef, Literal, Union

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    StrictInt,
    StrictStr,
    WithJsonSchema,
    create_model,
    with_config,
)
from typing_extensions import TypeAliasType, TypedDict

from emulator.scenario_model import Number, Positive, ScenarioFile, Text

__all__ = ["SCHEMA", "SCHEMA_PATH", "Budget", "OracleOp", "SessionFile", "SessionHeader",
           "TaskFile", "json_schema", "schema_text"]

SCHEMA: Literal["mavswarm.session/1"] = "mavswarm.session/1"
SCHEMA_PATH = Path(__file__).resolve().parent / "session.schema.json"


class Budget(BaseModel):
    """What a task may spend: tool calls and simulated seconds."""

    model_config = ConfigDict(extra="ignore")

    tool_calls: StrictInt = Field(ge=1)
    sim_time_s: Positive


@with_config(ConfigDict(extra="allow"))
class OracleOp(TypedDict):
    """One operation of the reference plan (`swarm_agents.oracle`): its kind and arguments."""

    op: Annotated[StrictStr, Field(description="goto, takeoff, photo, ... (swarm_agents.oracle)")]


class TaskFile(BaseModel):
    """One task. `checks`, `oracle` and `faults` are hidden from agents."""

    model_config = ConfigDict(extra="ignore")

    id: Annotated[Any, WithJsonSchema({"type": "string", "minLength": 1,
                                       "description": "unique in the session; default #1, "
                                                      "#2, ... by position"})] = None
    template: StrictStr = "custom"
    category: StrictStr = "uncategorised"
    difficulty: Literal["easy", "medium", "hard"] = "medium"
    text: Text = Field(description="what the agent is told")
    aliases: list[StrictStr] = Field(default_factory=list, description="other phrasings")
    budget: Budget
    checks: Annotated[Any, WithJsonSchema({
        "description": "the check tree: {logic, checks} nodes over {endpoint, parameters} "
                       "leaves (benchmark.scoring.validators)"})] = Field()
    oracle: list[list[OracleOp]] | None = Field(
        None, description="the reference plan: phases of operations (phases run in order, "
                          "the operations of a phase side by side)")
    faults: dict[str, Any] | None = Field(
        None, description="hidden faults: {failures, link} (benchmark.authoring.task_faults)")


def _schema_models() -> tuple[type[BaseModel], ...]:
    """The task and the session as the schema publishes them, with the check tree typed
    (canonical form: endpoint names as registered, `expect` a boolean): a group, a leaf of
    one endpoint with that endpoint's parameters (`benchmark.scoring.validators`' models), or a list
    (an "and" group). Loading reads the tree with `benchmark.scoring.validators.parse_tree`, which
    also takes the reference's spellings. Built on first use (41 endpoint models)."""
    from benchmark.scoring.validators.endpoint import params_model
    from benchmark.scoring.validators.registry import ENDPOINTS

    notes: dict[str, Any] = {"name": (str | None, None), "description": (str | None, None)}
    leaves = tuple(
        create_model(f"check_{name}", __config__=ConfigDict(extra="forbid"),
                     __doc__=endpoint.description, **{
                         "endpoint": (Literal[name], ...), "expect": (bool, True),
                         "parameters": (params_model(endpoint) | None, None), **notes})
        for name, endpoint in sorted(ENDPOINTS.items()))
    leaf: Any = Annotated[Union[leaves], Field(discriminator="endpoint")]  # noqa: UP007
    node: Any = TypeAliasType("CheckNode", Union[  # noqa: UP007
        leaf, ForwardRef("CheckGroup"), list[ForwardRef("CheckNode")]])  # type: ignore[misc]
    group_fields: dict[str, Any] = {"logic": (Literal["and", "or", "not"], "and"),
                                    "checks": (list[node], Field(default_factory=list)),
                                    **notes}
    group = create_model("CheckGroup", __config__=ConfigDict(extra="forbid"),
                         __doc__="and: all children pass; or: any passes; not: not all pass",
                         **group_fields)
    checks: dict[str, Any] = {"checks": (node, Field(
        description=TaskFile.model_fields["checks"].description))}
    task = create_model("TaskFile", __base__=TaskFile, __doc__=TaskFile.__doc__, **checks)
    tasks: dict[str, Any] = {"tasks": (list[task], ...)}  # type: ignore[valid-type]
    session = create_model("SessionFile", __base__=SessionFile, __doc__=SessionFile.__doc__,
                           **tasks)
    namespace = {"CheckGroup": group, "CheckNode": node}
    for model in (group, task, session):
        model.model_rebuild(_types_namespace=namespace)
    return group, task, session


class SessionHeader(ScenarioFile):
    """What loading checks of the whole file (the tasks are checked one by one)."""

    schema_: Literal["mavswarm.session/1"] = Field(alias="schema")
    id: StrictStr
    family: StrictStr = Field(description="the generator's family, or an imported file's task "
                                          "type")
    level: StrictStr = Field(description="easy ... extreme, or imported")
    index: StrictInt = 0
    tasks: list[Any]


class SessionFile(SessionHeader):
    """A benchmark session file: a scenario, its identity and its ordered tasks."""

    description: str = ""
    seed: int | None = Field(None, description="the generator's seed (null: imported)")
    map_size_m: tuple[Number, Number] | None = Field(None, description="[width, height]")
    tasks: list[TaskFile]  # the tasks' shape (the published schema types their checks)
    link_faults: dict[str, Any] | None = Field(
        None, description="the session's link faults (emulator.link_faults)")


def json_schema() -> dict[str, Any]:
    """The JSON Schema of a session file."""
    schema = _schema_models()[-1].model_json_schema(by_alias=True)
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["$id"] = "https://mavswarm.dev/schemas/session-1.json"
    return schema


def schema_text() -> str:
    """The JSON Schema file's text, as generated from the models."""
    return json.dumps(json_schema(), indent=2, sort_keys=True) + "\n"


if __name__ == "__main__":
    SCHEMA_PATH.write_text(schema_text(), encoding="utf-8")
    print(f"wrote {SCHEMA_PATH}")
