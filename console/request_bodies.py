"""The JSON bodies the console's routes take, as pydantic models: parsed within the input
bounds of every surface (`llm_tools.body_limit.json_body`), then validated here, so a bad
body is a 422 naming the field."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, Field

from benchmark.session_folders import MAX_SESSION_PATH_CHARS
from llm_tools.input_limits import MAX_NAME_CHARS

__all__ = ["CommandBody", "EditorSaveBody"]


class CommandBody(BaseModel):
    """`POST /api/live/{id}/command`: one console command for one drone."""

    model_config = ConfigDict(extra="forbid")
    drone_id: str = Field(max_length=MAX_NAME_CHARS)
    tool: str = Field(max_length=MAX_NAME_CHARS)
    args: dict[str, Any] | None = None


class EditorSaveBody(BaseModel):
    """`POST /api/editor/save`: the session the editor made and where to save it (a .json
    path under the editor's save folder)."""

    model_config = ConfigDict(extra="forbid")
    path: str = Field(min_length=1, max_length=MAX_SESSION_PATH_CHARS)
    session: dict[str, Any]
