"""Tool arguments: one pydantic model per tool from its signature and docstring (read by
docstring-parser) gives both the published schema and the checker; problems name the argument
path and say what is wrong."""

from __future__ import annotations

from typing import Literal

import pytest

from llm_tools.registry import ToolRegistry
from llm_tools.schema import arguments_model, describe, model_schema, schema_for, validate


def example(self: object, drone_id: str, speed_m_s: float, mode: Literal["a", "b"] = "a",
            points: list[list[float]] | None = None, note: str = "") -> None:
    """Fly somewhere.

    Longer text
    on two lines.

    Args:
        drone_id: The drone.
        speed_m_s (float): Ground speed in m/s,
            continued on a second line.
        mode: How.
        points: Where.

    Returns:
        Nothing.
    """


def test_the_docstring_gives_the_summary_and_the_descriptions() -> None:
    summary, params = describe(example)
    assert summary == "Fly somewhere. Longer text on two lines."
    assert params == {"drone_id": "The drone.",
                      "speed_m_s": "Ground speed in m/s, continued on a second line.",
                      "mode": "How.", "points": "Where."}


def test_the_schema_is_generated_from_the_model() -> None:
    schema = schema_for(example)
    assert schema == {
        "type": "object", "additionalProperties": False,
        "required": ["drone_id", "speed_m_s"],
        "properties": {
            "drone_id": {"type": "string", "description": "The drone."},
            "speed_m_s": {"type": "number", "description": "Ground speed in m/s, continued on "
                                                           "a second line."},
            "mode": {"type": "string", "enum": ["a", "b"], "default": "a",
                     "description": "How."},
            "points": {"type": "array", "items": {"type": "array", "items": {"type": "number"}},
                       "default": None, "description": "Where."},
            "note": {"type": "string", "default": ""}}}
    assert schema == model_schema(arguments_model(example))


@pytest.mark.parametrize(("arguments", "problems"), [
    ({"drone_id": "d1", "speed_m_s": 2}, []),
    ({"drone_id": "d1"}, ["missing required argument(s) 'speed_m_s'"]),
    ({}, ["missing required argument(s) 'drone_id', 'speed_m_s'"]),
    ({"drone_id": "d1", "speed_m_s": 1, "fast": True, "slow": 1},
     ["unknown argument(s) 'fast', 'slow'; expected drone_id, speed_m_s, mode, points, note"]),
    ({"drone_id": 7, "speed_m_s": True},
     ["drone_id must be a string, got 7", "speed_m_s must be a number, got True"]),
    ({"drone_id": "d1", "speed_m_s": 1e12},
     ["speed_m_s is 1e+12; numbers are limited to +/-1e+09"]),
    ({"drone_id": "d1", "speed_m_s": None}, ["speed_m_s must be a number, got None"]),
    ({"drone_id": "d1", "speed_m_s": 1, "mode": "c"},
     ["mode must be one of ['a', 'b'], got 'c'"]),
    ({"drone_id": "d1", "speed_m_s": 1, "points": [[1, 2], [3, "x"]]},
     ["points[1][1] must be a number, got 'x'"]),
    ({"drone_id": "d1", "speed_m_s": 1, "points": "here"},
     ["points must be a list, got 'here'"]),
    ({"drone_id": "d1", "speed_m_s": 1, "note": "a\x00"},
     ["note holds a control character (U+0000) at character 1; send valid Unicode text"]),
    ([1], ["arguments must be a JSON object, got a list of 1 items"]),
])
def test_problems_name_the_argument_and_the_reason(arguments: object,
                                                   problems: list[str]) -> None:
    values, found = validate(arguments, arguments_model(example))
    assert found == problems
    if not problems:
        assert values == {"drone_id": "d1", "speed_m_s": 2.0}
        assert isinstance(values["speed_m_s"], float)


def test_every_tool_validates_with_the_model_its_schema_came_from() -> None:
    registry = ToolRegistry(batch=True)
    for spec in registry.specs():
        assert spec.arguments is not None
        if spec.name != "batch":
            assert spec.input_schema == model_schema(spec.arguments)
    batch = registry.get("batch")
    assert batch is not None and batch.arguments is not None
    assert validate({"calls": []}, batch.arguments)[1] == [
        "calls needs at least 1 item(s), got 0"]
