"""What `mavswarm replay` opens: benchmark results folders (runs -> sessions -> tasks, with
each task's replay data where `bench run` stored it) and ground-truth files.

A results folder holds `results.jsonl` and, from runs that keep replays, `replay/` (see
`benchmark.running.replay_data`). Older results have no `replay/`: their tasks still list, with a
note
that no replay was recorded.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from benchmark.reporting.compare.build import build_compare, summarize_run
from benchmark.reporting.compare.runs import Run, runs_of_records
from benchmark.running.replay_data import (
    encode_window,
    read_json_gz,
    replay_path,
    session_world,
    world_path,
)
from benchmark.running.results import ResultsError, read_records
from emulator.truth import TruthLog

__all__ = ["NO_REPLAY_NOTE", "ReplayIndex", "ResultsRun", "TruthReplay", "open_paths"]

NO_REPLAY_NOTE = ("no replay was recorded for this task: these results were written before "
                  "`bench run` kept replay data (or the replay folder was removed); the "
                  "verdicts and checks are shown without the map")
FILTER_FIELDS = ("family", "level", "category", "template", "agent")


@dataclass
class ResultsRun:
    """One results folder."""

    id: str
    path: Path
    records: list[dict[str, Any]] = field(default_factory=list)

    @classmethod
    def load(cls, run_id: str, path: Path) -> ResultsRun:
        return cls(run_id, path, read_records(path / "results.jsonl"))

    def summary(self) -> dict[str, Any]:
        agents = sorted({str(r.get("agent")) for r in self.records})
        passed = sum(1 for r in self.records if r.get("passed"))
        return {"id": self.id, "path": str(self.path), "agents": agents,
                "tasks": len(self.records), "passed": passed,
                "sessions": len({r.get("session") for r in self.records})}

    def rows(self) -> list[dict[str, Any]]:
        """One row per record: what the task list shows and filters on."""
        out = []
        for r in self.records:
            endpoints = sorted({str(c.get("endpoint")) for c in r.get("checks") or []})
            failed = [c for c in r.get("checks") or [] if not c.get("passed")]
            row = {k: r.get(k) for k in ("key", "session", "task", "trial", "passed",
                                          "finish", "checks_passed", "checks_total",
                                          "tool_calls", "sim_time_s", *FILTER_FIELDS)}
            row["endpoints"] = endpoints
            row["failed_endpoints"] = sorted({str(c.get("endpoint")) for c in failed})
            row["has_replay"] = self.replay_file(r).exists()
            out.append(row)
        return out

    def replay_file(self, record: dict[str, Any]) -> Path:
        return replay_path(self.path, str(record["session"]), str(record["task"]),
                           str(record["agent"]), int(record.get("trial", 0)))

    def find(self, session: str, task: str, trial: int, agent: str | None
             ) -> dict[str, Any] | None:
        for r in self.records:
            if (r.get("session") == session and r.get("task") == task
                    and int(r.get("trial", 0)) == trial
                    and (agent is None or r.get("agent") == agent)):
                return r
        return None

    def task_view(self, record: dict[str, Any]) -> dict[str, Any]:
        """A task page's data: the record, and its replay and world when they were kept."""
        view: dict[str, Any] = {"run": self.id, "record": record, "replay": None,
                                "world": None, "note": None}
        path = self.replay_file(record)
        if not path.exists():
            view["note"] = NO_REPLAY_NOTE
            return view
        try:
            view["replay"] = read_json_gz(path)
            wpath = world_path(self.path, str(record["session"]))
            view["world"] = read_json_gz(wpath) if wpath.exists() else None
        except (OSError, ValueError, EOFError) as error:
            view["note"] = f"the replay file {path} cannot be read: {error}"
        return view


@dataclass
class TruthReplay:
    """A ground-truth file (`*.truth.npz`) replayed whole."""

    path: Path
    world: dict[str, Any] | None
    note: str | None

    @classmethod
    def load(cls, path: Path, session: Path | None = None) -> TruthReplay:
        world, note = None, None
        if session is not None:
            world = session_world(json.loads(session.read_text(encoding="utf-8")))
        else:
            text = TruthLog.attachment(path, "scenario")
            if text is not None:
                world = json.loads(text)
            else:
                note = ("this truth file carries no scenario (written by an older mavswarm): "
                        "paths are shown without the world; pass --session FILE to add it")
        return cls(path, world, note)

    def view(self) -> dict[str, Any]:
        log = TruthLog.load(self.path)
        return {"replay": encode_window(log), "world": self.world, "note": self.note,
                "name": self.path.name}


@dataclass
class ReplayIndex:
    """Everything one `mavswarm replay` serves."""

    runs: dict[str, ResultsRun] = field(default_factory=dict)
    truth: TruthReplay | None = None
    _board: list[dict[str, Any]] | None = field(default=None, repr=False)

    def agent_runs(self) -> dict[str, Run]:
        """Every (run, agent) the served results hold, as compared runs: id ``RUN`` or, for a
        run of several agents, ``RUN:agent``."""
        out: dict[str, Run] = {}
        for run in self.runs.values():
            if not run.records:
                continue
            for agent_run in runs_of_records(run.id, run.path / "results.jsonl", run.id,
                                             run.records):
                out[agent_run.id] = agent_run
        return out

    def leaderboard(self) -> list[dict[str, Any]]:
        """One row per (run, agent): its metrics with session-clustered 95 % intervals
        (computed once; the served results do not change)."""
        if self._board is None:
            self._board = [summarize_run(run).model_dump(exclude={"by_template"})
                           for run in self.agent_runs().values()]
        return self._board

    def compare(self, baseline: str, other: str) -> dict[str, Any]:
        """`other` against `baseline` (ids from :meth:`agent_runs`) on the tasks both ran.
        Raises KeyError naming an unknown id, ValueError for runs that cannot be compared."""
        runs = self.agent_runs()
        for name in (baseline, other):
            if name not in runs:
                raise KeyError(f"no run {name!r}; runs: {', '.join(runs) or 'none'}")
        if baseline == other:
            raise ValueError("pick two different runs to compare")
        return build_compare([runs[baseline], runs[other]], intersect=True).model_dump()


def _run_folders(path: Path) -> list[Path]:
    if (path / "results.jsonl").exists():
        return [path]
    return sorted(p.parent for p in path.glob("*/results.jsonl"))


def open_paths(paths: Sequence[Path], session: Path | None = None) -> ReplayIndex:
    """An index of `paths`: results folders (or folders of them) and at most one truth file.
    Raises ValueError naming the path that cannot be opened."""
    index = ReplayIndex()
    for path in paths:
        if path.is_file() and path.name.endswith(".npz"):
            if index.truth is not None:
                raise ValueError(f"{path}: one truth file at a time")
            try:
                index.truth = TruthReplay.load(path, session)
            except (OSError, ValueError, KeyError) as error:
                raise ValueError(f"{path}: not a readable truth file: {error}") from None
            continue
        if not path.is_dir():
            raise ValueError(f"{path}: neither a results folder nor a *.truth.npz file")
        folders = _run_folders(path)
        if not folders:
            raise ValueError(f"{path}: no results.jsonl in it or in its sub-folders")
        for folder in folders:
            run_id = folder.name or "run"
            while run_id in index.runs:
                run_id += "+"
            try:
                index.runs[run_id] = ResultsRun.load(run_id, folder)
            except ResultsError as error:
                raise ValueError(str(error)) from None
    return index
