"""The JSON bodies the console's routes take, as pydantic models: parsed within the input
bounds of every surface (`llm_tools.body_limit.json_body`), then validated here, so a bad
body is a 422 naming the field."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from benchmark.authoring.session_folders import MAX_SESSION_PATH_CHARS
from llm_tools.input_limits import MAX_NAME_CHARS, MAX_STRING_CHARS

MAX_TEMPLATE_CHARS = MAX_STRING_CHARS

__all__ = ["CommandBody", "EditorSaveBody", "InstantiateBody", "ProveBody", "RecheckBody",
           "TemplateTextBody"]


Name = Annotated[str, Field(max_length=MAX_NAME_CHARS)]
TemplateText = Annotated[str, Field(min_length=1, max_length=MAX_TEMPLATE_CHARS,
                                    description="a template file's text (mavswarm.template/1)")]
MAX_TEMPLATES_DRAWN = 20


class CommandBody(BaseModel):
    """`POST /api/live/{id}/command`: a console command for one drone (`drone_id`) or a
    selection (`drone_ids`: a list, or "all"), with `args` for every drone and
    `args_by_drone` for some (console.live_routes)."""

    model_config = ConfigDict(extra="forbid")
    drone_id: Name | None = None
    drone_ids: list[Name] | Literal["all"] | None = None
    tool: Name
    args: dict[str, Any] | None = None
    args_by_drone: dict[Name, dict[str, Any]] | None = None

    @model_validator(mode="after")
    def _one_target(self) -> CommandBody:
        if (self.drone_id is None) == (self.drone_ids is None):
            raise ValueError("send drone_id (one drone) or drone_ids (a list of ids, or "
                             "\"all\"), one of them")
        if self.drone_ids == []:
            raise ValueError("drone_ids is empty: name at least one drone, or \"all\"")
        return self


class EditorSaveBody(BaseModel):
    """`POST /api/editor/save`: the session the editor made and where to save it (a .json
    path under the editor's save folder)."""

    model_config = ConfigDict(extra="forbid")
    path: str = Field(min_length=1, max_length=MAX_SESSION_PATH_CHARS)
    session: dict[str, Any]


class TemplateTextBody(BaseModel):
    """`POST /api/editor/templates/validate` and `.../save`: a template file's text."""

    model_config = ConfigDict(extra="forbid")
    text: TemplateText


class InstantiateBody(BaseModel):
    """`POST /api/editor/templates/instantiate`: draw `count` tasks of the template `text` on
    the world of `session` (the editor's), seeded by `seed`."""

    model_config = ConfigDict(extra="forbid")
    session: dict[str, Any]
    text: TemplateText
    count: int = Field(default=1, ge=1, le=MAX_TEMPLATES_DRAWN)
    seed: int = Field(default=1, ge=0, le=2**31 - 1)


class RecheckBody(BaseModel):
    """`POST /api/editor/tasks/recheck`: every task of `session` against its world."""

    model_config = ConfigDict(extra="forbid")
    session: dict[str, Any]


class ProveBody(BaseModel):
    """`POST /api/editor/proofs`: prove task `task_id` of `session` with the oracle."""

    model_config = ConfigDict(extra="forbid")
    session: dict[str, Any]
    task_id: Name = Field(min_length=1)
