"""The workflow agent's memory for one task: what its tools have reported and nothing else.

Every fact enters through `Blackboard.ingest`, which reads one tool result: drone states from
`list_drones`, `drone_state` and any result carrying a drone's state; targets, obstacles and
other drones from `nearby`; inbox contents from `read_messages`. Error results add nothing but
a note. The blackboard never consults the world, the session or the task's hidden data.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

__all__ = ["Blackboard", "SensedEntity", "StepRecord"]

MAX_NOTES = 40
MAX_MESSAGES = 40


@dataclass(frozen=True)
class SensedEntity:
    """A target, obstacle or drone as a drone's sensor last reported it."""

    entity_id: str
    category: str  # "target", "obstacle" or "drone"
    kind: str
    position_m: tuple[float, ...]
    distance_m: float
    seen_by: str
    seen_at_step: int

    def to_dict(self) -> dict[str, Any]:
        return {"id": self.entity_id, "category": self.category, "kind": self.kind,
                "position": list(self.position_m), "distance_m": self.distance_m,
                "seen_by": self.seen_by}


@dataclass(frozen=True)
class StepRecord:
    """One tool call the agent made and how it ended."""

    tool: str
    arguments: Mapping[str, Any] | str | None
    status: str
    message: str

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    def describe(self) -> str:
        args = self.arguments if isinstance(self.arguments, str) else \
            json.dumps(self.arguments or {}, separators=(",", ":"), sort_keys=True)
        return f"{self.tool}({args}) -> {self.status}: {self.message}"


_CATEGORIES = {"targets": "target", "obstacles": "obstacle", "drones": "drone"}


class Blackboard:
    """Drones' last states, sensed entities by id, received messages, notes and the step log."""

    def __init__(self) -> None:
        self.drones: dict[str, dict[str, Any]] = {}
        self.targets: dict[str, SensedEntity] = {}
        self.obstacles: dict[str, SensedEntity] = {}
        self.peers: dict[str, SensedEntity] = {}
        self.messages: list[dict[str, Any]] = []
        self.notes: list[str] = []
        self.steps: list[StepRecord] = []
        self._sense_count = 0

    # ------------------------------------------------------------------ input
    def ingest(self, tool: str, arguments: Mapping[str, Any] | str | None,
               result: Mapping[str, Any]) -> StepRecord:
        """Record one tool call and learn what its result reports."""
        status = str(result.get("status", "error"))
        record = StepRecord(tool, arguments, status, str(result.get("message", ""))[:400])
        self.steps.append(record)
        if status != "ok":
            self.add_note(record.describe())
        state = result.get("state")
        if isinstance(state, Mapping):
            self._store_state(state)
        drones = result.get("drones")
        if tool == "list_drones" and isinstance(drones, list):
            for entry in drones:
                if isinstance(entry, Mapping):
                    self._store_state(entry)
        if tool == "nearby" and status == "ok":
            self._store_perception(_drone_of(arguments, state), result)
        if tool == "read_messages" and isinstance(result.get("messages"), list):
            receiver = _drone_of(arguments, state)
            for message in result["messages"]:
                if isinstance(message, Mapping):
                    self.messages.append({"to": receiver, **dict(message)})
            del self.messages[:-MAX_MESSAGES]
        return record

    def add_note(self, text: str) -> None:
        """A free-text note (kept to the latest few)."""
        self.notes.append(str(text)[:500])
        del self.notes[:-MAX_NOTES]

    def _store_state(self, state: Mapping[str, Any]) -> None:
        drone = state.get("drone")
        if isinstance(drone, str) and drone:
            self.drones[drone] = dict(state)

    def _store_perception(self, seen_by: str, result: Mapping[str, Any]) -> None:
        self._sense_count += 1
        stores = {"targets": self.targets, "obstacles": self.obstacles, "drones": self.peers}
        for key, store in stores.items():
            entries = result.get(key)
            if not isinstance(entries, list):
                continue
            for entry in entries:
                entity = _entity(entry, _CATEGORIES[key], seen_by, self._sense_count)
                if entity is not None and entity.entity_id != seen_by:
                    store[entity.entity_id] = entity

    # ----------------------------------------------------------------- output
    def failures(self, since: int = 0) -> list[StepRecord]:
        """Steps from index `since` on that did not end "ok"."""
        return [s for s in self.steps[since:] if not s.ok]

    def to_dict(self) -> dict[str, Any]:
        return {
            "drones": {k: _compact_state(v) for k, v in sorted(self.drones.items())},
            "targets": [e.to_dict() for e in self.targets.values()],
            "obstacles": [e.to_dict() for e in self.obstacles.values()],
            "other_drones_sensed": [e.to_dict() for e in self.peers.values()],
            "messages": list(self.messages),
            "notes": list(self.notes),
        }

    def summary(self) -> str:
        """The blackboard as compact JSON text for a prompt."""
        return json.dumps(self.to_dict(), separators=(",", ":"))

    def known_ids(self) -> set[str]:
        """Every drone, target and obstacle id the blackboard holds."""
        return set(self.drones) | set(self.targets) | set(self.obstacles) | set(self.peers)


def _drone_of(arguments: Mapping[str, Any] | str | None,
              state: Any) -> str:
    if isinstance(state, Mapping) and isinstance(state.get("drone"), str):
        return str(state["drone"])
    if isinstance(arguments, Mapping) and isinstance(arguments.get("drone_id"), str):
        return str(arguments["drone_id"])
    return ""


def _entity(entry: Any, category: str, seen_by: str, step: int) -> SensedEntity | None:
    if not isinstance(entry, Mapping) or not isinstance(entry.get("id"), str):
        return None
    raw = entry.get("position")
    position: tuple[float, ...] = ()
    if isinstance(raw, list | tuple) and all(isinstance(v, int | float) for v in raw):
        position = tuple(float(v) for v in raw)
    distance = entry.get("distance_m")
    return SensedEntity(entry["id"], category, str(entry.get("kind", "")), position,
                        float(distance) if isinstance(distance, int | float) else float("nan"),
                        seen_by, step)


def _compact_state(state: Mapping[str, Any]) -> dict[str, Any]:
    keys = ("x_m", "y_m", "altitude_m", "heading_deg", "battery_pct", "flight_state",
            "home_x_m", "home_y_m")
    return {k: state[k] for k in keys if k in state}
