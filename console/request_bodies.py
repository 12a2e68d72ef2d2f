"""The JSON bodies the console's routes take, as pydantic models: parsed within the input
bounds of every surface (`llm_tools.body_limit.json_body`), then validated here, so a bad
body is a 422 naming the field."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from benchmark.authoring.session_folders import MAX_SESSION_PATH_CHARS
from llm_tools.input_limits import MAX_NAME_CHARS

__all__ = ["CommandBody", "EditorSaveBody"]


Name = Annotated[str, Field(max_length=MAX_NAME_CHARS)]


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
