"""Failing check leaves of result records, described for a reader: which check, on what,
the value it measured and the threshold it was held to (as the records hold them).

A leaf's ``parameters`` mix what a check is about (a drone, a target, a point) with the
limits it applies (``tolerance``, ``min_*``, ``max_*``, ``expected_*``, ``*_threshold``);
the second kind is shown as the threshold beside the measured ``value``.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from benchmark.scoring.validators.registry import ENDPOINTS

__all__ = ["FailedLeaf", "failed_leaves", "format_value", "is_threshold"]

_POINT_KEYS = ("x", "y", "z")


def is_threshold(name: str) -> bool:
    """Whether a check parameter named `name` is a limit the measured value is held to."""
    return (name == "tolerance" or name.startswith(("min_", "max_", "expected_"))
            or name.endswith("_threshold"))


def format_value(value: Any) -> str:
    """A compact, readable rendering of a measured value or parameter."""
    if value is None:
        return "none"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return f"{value:.3f}".rstrip("0").rstrip(".") if abs(value) < 1e6 else f"{value:.4g}"
    if isinstance(value, int | str):
        return str(value)
    if isinstance(value, Mapping) and set(value) <= {"x", "y", "z"}:
        return "(" + ", ".join(format_value(value[k]) for k in _POINT_KEYS if k in value) + ")"
    if isinstance(value, Sequence):
        return "[" + ", ".join(format_value(v) for v in value) + "]"
    return json.dumps(value, sort_keys=True, default=str)


@dataclass(frozen=True)
class FailedLeaf:
    """One failing leaf check, ready to show."""

    path: str
    endpoint: str
    condition: str  # what the check requires (the endpoint's description)
    subject: str  # what it is about: ids and points
    measured: str
    threshold: str  # the limits it applies, "" when it has none
    note: str  # an error, or what the check tree expected when it wanted "false"


def _subject(parameters: Mapping[str, Any]) -> str:
    parts = []
    point = {k: parameters[k] for k in _POINT_KEYS if parameters.get(k) is not None}
    for name, value in parameters.items():
        if value is None or name in _POINT_KEYS or is_threshold(name):
            continue
        shown = format_value(value)
        if name == "to_drone_id":
            parts.append(f"to {shown}")
        elif name.endswith(("_id", "_ids")):
            parts.append(shown)
        else:
            parts.append(f"{name} {shown}")
    if point:
        parts.append("at " + format_value(point))
    return ", ".join(parts)


def _thresholds(parameters: Mapping[str, Any]) -> str:
    return ", ".join(f"{name} {format_value(value)}" for name, value in parameters.items()
                     if value is not None and is_threshold(name))


def _leaf(check: Mapping[str, Any]) -> FailedLeaf:
    endpoint = str(check.get("endpoint", "?"))
    known = ENDPOINTS.get(endpoint)
    raw = check.get("parameters")
    parameters: Mapping[str, Any] = raw if isinstance(raw, Mapping) else {}
    notes = []
    if check.get("error"):
        notes.append(f"error: {check['error']}")
    if check.get("expect") is False:
        notes.append("the task wanted this check false; it was "
                     f"{format_value(check.get('result'))}")
    return FailedLeaf(path=str(check.get("path", "")), endpoint=endpoint,
                      condition=known.description if known is not None else "",
                      subject=_subject(parameters), measured=format_value(check.get("value")),
                      threshold=_thresholds(parameters), note="; ".join(notes))


def failed_leaves(record: Mapping[str, Any]) -> list[FailedLeaf]:
    """The failing leaf checks of one record, in check order."""
    checks = record.get("checks")
    if not isinstance(checks, list):
        return []
    return [_leaf(c) for c in checks if isinstance(c, Mapping) and c.get("passed") is not True]
