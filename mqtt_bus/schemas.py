"""A JSON Schema for every payload the bus carries, by topic kind (see mqtt_bus.topics).

`python -m mqtt_bus.schemas` prints them all as one JSON document.
"""

from __future__ import annotations

import json
from typing import Any

from agent_contract.tools import RESULT_STATUSES
from mavlink_vocabulary import TELEMETRY_FLIGHT_STATES
from mqtt_bus.payloads import FAILSAFE_ACTIONS, FAILSAFE_REASONS

__all__ = ["SCHEMAS"]

_NUM = {"type": ["number", "null"]}  # null: not reported (e.g. a battery not yet heard)
_XYZ = {"type": "object", "additionalProperties": False,
        "required": ["x_m", "y_m", "z_m"],
        "properties": {"x_m": _NUM, "y_m": _NUM, "z_m": _NUM}}
_DRONE = {"type": "string", "description": "the drone's id, as in the topic"}
_TIME = {"type": "number", "description": "simulated seconds (a bridge: seconds since it "
                                          "started)"}
_COMMON = {"drone": _DRONE, "time_s": _TIME}

OSD: dict[str, Any] = {
    "title": "{prefix}/{session}/{drone}/osd", "type": "object",
    "additionalProperties": False,
    "required": ["drone", "time_s", "position", "wgs84", "velocity", "heading_deg",
                 "battery_pct", "mode", "armed"],
    "properties": {
        **_COMMON,
        "position": {"type": "object", "additionalProperties": False,
                     "description": "local ENU metres from the session origin's ground; "
                                    "altitude_m above home",
                     "required": ["x_m", "y_m", "z_m", "altitude_m"],
                     "properties": {"x_m": _NUM, "y_m": _NUM, "z_m": _NUM,
                                    "altitude_m": _NUM}},
        "wgs84": {"type": "object", "additionalProperties": False,
                  "required": ["latitude_deg", "longitude_deg", "altitude_amsl_m"],
                  "properties": {"latitude_deg": _NUM, "longitude_deg": _NUM,
                                 "altitude_amsl_m": _NUM}},
        "velocity": {"type": "object", "additionalProperties": False,
                     "required": ["east_m_s", "north_m_s", "up_m_s"],
                     "properties": {"east_m_s": _NUM, "north_m_s": _NUM, "up_m_s": _NUM}},
        "heading_deg": _NUM, "battery_pct": _NUM,
        "mode": {"type": "string", "description": "PX4 mode, lower case (hold, mission, ...)"},
        "armed": {"type": "boolean"},
    },
}

STATE: dict[str, Any] = {
    "title": "{prefix}/{session}/{drone}/state (retained, on change)", "type": "object",
    "additionalProperties": False,
    "required": ["drone", "time_s", "flight_state", "mode", "armed", "home", "primitive"],
    "properties": {
        **_COMMON,
        "flight_state": {"enum": [s.value for s in TELEMETRY_FLIGHT_STATES]},
        "mode": {"type": "string"}, "armed": {"type": "boolean"},
        "home": {"oneOf": [{"type": "null"}, {
            "type": "object", "additionalProperties": False,
            "required": ["x_m", "y_m", "z_m", "latitude_deg", "longitude_deg",
                         "altitude_amsl_m"],
            "properties": {k: _NUM for k in ("x_m", "y_m", "z_m", "latitude_deg",
                                             "longitude_deg", "altitude_amsl_m")}}]},
        "primitive": {"type": ["string", "null"],
                      "description": "the gateway primitive running for the drone"},
    },
}

_EVENT_BASE = {**_COMMON, "kind": {"type": "string"},
               "severity": {"type": ["integer", "null"],
                            "description": "MAV_SEVERITY (null: not reported)"},
               "text": {"type": "string"}}
EVENTS: dict[str, Any] = {
    "title": "{prefix}/{session}/{drone}/events", "type": "object",
    "required": ["drone", "time_s", "kind"],
    "oneOf": [
        {"properties": {**_EVENT_BASE, "kind": {"const": "statustext"}},
         "required": ["severity", "text"], "additionalProperties": False},
        {"properties": {**_EVENT_BASE, "kind": {"const": "obstacle_hold"},
                        "obstacle": {"type": "string"}},
         "required": ["severity", "text", "obstacle"], "additionalProperties": False},
        {"properties": {**_EVENT_BASE, "kind": {"const": "failsafe"},
                        "reason": {"enum": list(FAILSAFE_REASONS)},
                        "action": {"enum": list(FAILSAFE_ACTIONS)}},
         "required": ["severity", "text", "reason", "action"], "additionalProperties": False},
        {"properties": {**_COMMON, "kind": {"const": "photo"},
                        "index": {"type": "integer"}, "position": _XYZ,
                        "targets": {"type": ["array", "null"], "items": {"type": "string"},
                                    "description": "targets in the photo's footprint, as "
                                                   "the drone's sensor perceived them "
                                                   "(null: unknown behind a bridge)"}},
         "required": ["index", "position", "targets"], "additionalProperties": False},
        {"properties": {**_COMMON, "kind": {"const": "radio"},
                        "to": {"type": ["string", "null"]}, "broadcast": {"type": "boolean"},
                        "text": {"type": "string"}},
         "required": ["to", "broadcast", "text"], "additionalProperties": False},
    ],
}

STATUS: dict[str, Any] = {
    "title": "{prefix}/{session}/status (retained; offline is the Last Will)",
    "type": "object", "required": ["status", "session"],
    "properties": {"status": {"enum": ["online", "offline"]}, "session": {"type": "string"},
                   "drones": {"type": "array", "items": {"type": "string"}},
                   "commands": {"type": "boolean"}},
}

SERVICES: dict[str, Any] = {
    "title": "{prefix}/{session}/{drone}/services (operators only)", "type": "object",
    "additionalProperties": False, "required": ["id", "tool"],
    "properties": {
        "id": {"type": "string", "pattern": "^[\\x21-\\x7e]{1,64}$",
               "description": "echoed in the reply"},
        "tool": {"type": "string", "description": "an agent tool that takes drone_id, or "
                                                  "get_link / set_link (an emulated swarm's "
                                                  "link faults)"},
        "args": {"type": "object", "description": "the tool's arguments; drone_id comes "
                                                  "from the topic"},
    },
}

SERVICES_REPLY: dict[str, Any] = {
    "title": "{prefix}/{session}/{drone}/services_reply", "type": "object",
    "required": ["id", "drone", "tool", "status", "message"],
    "properties": {
        "id": {"type": ["string", "null"]}, "drone": _DRONE, "tool": {"type": ["string",
                                                                              "null"]},
        "status": {"enum": list(RESULT_STATUSES)},
        "message": {"type": "string"},
        "state": {"type": "object", "description": "the drone's state after (as every "
                                                   "surface's tool results)"},
        "link": {"type": "object", "required": ["uplink", "downlink"],
                 "description": "get_link / set_link: the drone's link faults in force"},
    },
}

BENCH_TASKS: dict[str, Any] = {
    "title": "{prefix}/bench/{run}/tasks: one results.jsonl record without `checks`",
    "type": "object", "required": ["key", "session", "task", "passed"],
    "not": {"required": ["checks"]},
}

BENCH_PROGRESS: dict[str, Any] = {
    "title": "{prefix}/bench/{run}/progress (retained)", "type": "object",
    "required": ["run", "tasks", "passed", "failed"],
    "properties": {"run": {"type": "string"}, "tasks": {"type": "integer"},
                   "passed": {"type": "integer"}, "failed": {"type": "integer"},
                   "finished": {"type": "boolean"},
                   "records_in_results": {"type": "integer"}},
}

SCHEMAS: dict[str, dict[str, Any]] = {
    "osd": OSD, "state": STATE, "events": EVENTS, "status": STATUS, "services": SERVICES,
    "services_reply": SERVICES_REPLY, "bench_tasks": BENCH_TASKS,
    "bench_progress": BENCH_PROGRESS,
}

if __name__ == "__main__":
    print(json.dumps(SCHEMAS, indent=2))
