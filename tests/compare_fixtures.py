"""Result records built directly for the comparison and report tests (the fields `bench run`
writes), and results folders holding them. Not a conftest: test modules import what they use."""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

__all__ = ["record", "write_results"]

ENDPOINTS = ("drone_has_taken_off", "drone_has_visited_position")


def record(session: str, task: str, agent: str, passed: bool, *, trial: int = 0,
           family: str = "area_search", level: str = "easy", category: str = "navigation",
           template: str = "takeoff_hold", checks_passed: int | None = None,
           **extra: Any) -> dict[str, Any]:
    """A record of one task: two leaf checks (both pass when the task passed, unless
    `checks_passed` says how many of them pass)."""
    passing = (2 if passed else 0) if checks_passed is None else checks_passed
    checks = [{"path": f"checks[{k}]", "endpoint": endpoint, "passed": k < passing,
               "parameters": {}, "expect": True, "result": k < passing, "value": None,
               "error": None} for k, endpoint in enumerate(ENDPOINTS)]
    return {"key": f"{session}/{task}/{agent}/{trial}", "session": session, "family": family,
            "level": level, "task": task, "template": template, "category": category,
            "agent": agent, "trial": trial, "passed": passed, "checks": checks,
            "checks_total": 2, "checks_passed": passing, "finish": "finished", "error": None,
            "tool_calls": 3, "clock": "lockstep", "sim_time_s": 40.0, "wall_time_s": 0.5,
            "tokens": None, **extra}


def write_results(folder: Path, records: Iterable[Mapping[str, Any]]) -> Path:
    """`folder`/results.jsonl holding `records`; returns the folder."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "results.jsonl").write_text(
        "".join(json.dumps(dict(r)) + "\n" for r in records), encoding="utf-8")
    return folder
