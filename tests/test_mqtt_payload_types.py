"""The MQTT payload schemas are generated from the typed dicts the builders return: every
builder's output meets its type and its published schema, and the schemas are closed where
the types are (a key a builder does not produce is refused)."""

from __future__ import annotations

import typing
from typing import Any

import jsonschema
import pytest
from pydantic import TypeAdapter, ValidationError

from agent_contract.tools import RESULT_STATUSES
from mqtt_bus import payload_types
from mqtt_bus.payloads import (
    DroneSample,
    bench_progress_payload,
    bench_status_payload,
    osd_payload,
    photo_event,
    radio_event,
    state_payload,
    status_payload,
    statustext_event,
)
from mqtt_bus.schemas import PAYLOAD_TYPES, SCHEMAS

SAMPLE = DroneSample("d1", 12.3456, (1.234, -5.0, float("nan")), (47.1, 8.2, 498.0),
                     (1.0, 2.0, 0.5), 359.96, 87.25, "mission", True, "flying", None, None)
BUILT: list[tuple[str, Any]] = [
    ("osd", osd_payload(SAMPLE)),
    ("state", state_payload(SAMPLE)),
    ("state", state_payload(DroneSample("d2", 1.0, (0, 0, 0), (47.0, 8.0, 488.0), (0, 0, 0),
                                        0.0, 50.0, "hold", False, "on_ground", (0, 0, 0),
                                        (47.0, 8.0, 488.0), "take_off"))),
    ("events", statustext_event("d1", 1.0, 4, "Obstacle Tower A ahead: holding")),
    ("events", statustext_event("d1", 1.0, 2, "Critical battery 14%: returning home")),
    ("events", statustext_event("d1", 1.0, 2, "Emergency battery 5%: landing")),
    ("events", statustext_event("d1", 1.0, 4, "Geofence reached: holding")),
    ("events", statustext_event("d1", 1.0, None, "Landing detected")),
    ("events", photo_event("d1", 2.0, 3, (1.0, 2.0, 30.0), ["t1"])),
    ("events", photo_event("d1", 2.0, 4, (1.0, 2.0, 30.0), None)),
    ("events", radio_event("d1", 3.0, "hello", None)),
    ("events", radio_event("d1", 3.0, "hello", "d2")),
    ("status", status_payload(True, "s1", ["d1", "d2"], commands=True)),
    ("status", status_payload(False, "s1")),
    ("bench_status", bench_status_payload(True, "run-1")),
    ("bench_progress", bench_progress_payload(
        "run-1", {"tasks": 2, "passed": 1, "failed": 1},
        last={"key": "s1/t02", "session": "s1", "task": "t02", "passed": False, "x": 1})),
    ("bench_progress", bench_progress_payload("run-1", {"tasks": 2, "passed": 1, "failed": 1},
                                              records_in_results=2)),
]


@pytest.mark.parametrize(("kind", "payload"), BUILT,
                         ids=[f"{k}-{i}" for i, (k, _) in enumerate(BUILT)])
def test_every_builder_output_meets_its_type_and_its_published_schema(kind: str,
                                                                      payload: Any) -> None:
    TypeAdapter(PAYLOAD_TYPES[kind]).validate_python(payload, strict=True)
    jsonschema.validate(payload, SCHEMAS[kind])


@pytest.mark.parametrize("kind", ["osd", "state", "events", "bench_progress", "bench_status"])
def test_the_closed_schemas_refuse_a_key_no_builder_writes(kind: str) -> None:
    payload = dict(next(p for k, p in BUILT if k == kind), surprise=1)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(payload, SCHEMAS[kind])
    with pytest.raises(ValidationError):
        TypeAdapter(PAYLOAD_TYPES[kind]).validate_python(payload)


def test_the_builders_write_every_key_of_their_types() -> None:
    assert set(osd_payload(SAMPLE)) == payload_types.OsdPayload.__required_keys__
    assert set(state_payload(SAMPLE)) == payload_types.StatePayload.__required_keys__
    events = typing.get_args(typing.get_args(payload_types.EventPayload)[0])
    def kind(event_type: Any) -> str:
        return str(typing.get_args(typing.get_type_hints(event_type)["kind"])[0])
    kinds = {kind(e) for e in events}
    assert kinds == {p["kind"] for k, p in BUILT if k == "events"}
    for _, event in ((k, p) for k, p in BUILT if k == "events"):
        typed = next(e for e in events if kind(e) == event["kind"])
        assert set(event) == typed.__required_keys__


def test_the_reply_status_is_the_tools_status_and_the_request_id_one_pattern() -> None:
    assert SCHEMAS["services_reply"]["properties"]["status"]["enum"] == list(RESULT_STATUSES)
    assert SCHEMAS["services"]["properties"]["id"]["pattern"] == \
        payload_types.REQUEST_ID_PATTERN
    jsonschema.validate({"id": "r-1", "tool": "land", "args": {}}, SCHEMAS["services"])
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate({"id": "with space", "tool": "land"}, SCHEMAS["services"])


def test_bench_progress_says_the_last_task_then_the_end() -> None:
    counts = {"tasks": 3, "passed": 2, "failed": 1}
    after = bench_progress_payload("r", counts, last={"key": "k", "session": "s", "task": "t",
                                                      "passed": True, "checks": {}})
    assert after == {"run": "r", "tasks": 3, "passed": 2, "failed": 1,
                     "last": {"key": "k", "session": "s", "task": "t", "passed": True}}
    end = bench_progress_payload("r", counts, records_in_results=3)
    assert end == {"run": "r", "tasks": 3, "passed": 2, "failed": 1, "finished": True,
                   "records_in_results": 3}
