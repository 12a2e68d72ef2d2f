"""What a replay needs, compactly: the ground truth of one window (every drone's path and the
events) and the agent's tool calls, stored by `bench run` next to `results.jsonl`.

Paths are thinned before they are stored: a sample is dropped while the drone's path between
its neighbours stays within `TOLERANCE_M` of a straight, constant-speed line (and its heading
within `TOLERANCE_DEG`), so steady flight costs two samples a leg and braking keeps its shape.
Values are quantised (0.1 s, 0.1 m, 1 degree, 0.1 % battery) and delta-encoded as integers, and
the whole is gzipped JSON (about 1-2 bytes a kept sample).

An LLM agent's transcript (`AgentTools.add_transcript`: its messages, tool calls with their
arguments in full, tokens per model turn, each at its simulated time) is kept in the task's
file under `transcript` (with `transcript_dropped`), not in results.jsonl. It is bounded where
it is recorded: 20,000 characters a text, 2,000 messages and 1,000,000 characters a task (see
`agent_contract.budget`), so at most about 1.2 MB of JSON (text and keys) before gzip.

Layout under a results folder::

    replay/<session>/world.json.gz                    the session's world (drones, targets,
                                                      obstacles as the session file has them)
    replay/<session>/<task>.<agent>.<trial>.json.gz   one task: window, paths, events, calls,
                                                      transcript
"""

from __future__ import annotations

import gzip
import json
import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from emulator.truth import TruthHistory

__all__ = ["FORMAT", "TOLERANCE_DEG", "TOLERANCE_M", "decode_paths", "encode_window",
           "read_json_gz", "replay_path", "session_world", "thin_rows", "world_path",
           "write_json_gz", "write_task_replay"]

FORMAT = "mavswarm.replay/1"
TOLERANCE_M = 0.1
TOLERANCE_DEG = 2.0
MAX_THIN_PASSES = 12
_SCALE = np.array([10.0, 10.0, 10.0, 10.0, 1.0, 10.0])  # t, x, y, z, yaw, battery
_COLUMNS = ("t", "x", "y", "z", "yaw", "bat")
_MAX_TEXT = 200
_SAFE = re.compile(r"[^A-Za-z0-9_.-]")


def thin_rows(rows: np.ndarray) -> np.ndarray:
    """The rows (t, x, y, z, yaw, battery) a replay keeps: first, last, and each one where
    linear interpolation between its kept neighbours would be off by more than the
    tolerances. Rows closer than 0.1 s to the previous kept one are merged first."""
    if rows.shape[0] <= 2:
        return rows
    t = rows[:, 0]
    bucket = np.floor((t - t[0]) * 10.0 + 1e-9)
    keep = np.ones(rows.shape[0], dtype=bool)
    keep[1:] = bucket[1:] != bucket[:-1]
    keep[-1] = True
    rows = rows[keep]
    columns = rows[:, :5].T.copy()  # t, x, y, z, yaw: each contiguous
    index = np.arange(rows.shape[0])
    for parity in range(MAX_THIN_PASSES * 2):
        if index.size <= 2:
            break
        t, x, y, z, yaw = columns[:, index]
        span = t[2:] - t[:-2]
        frac = np.where(span > 0, (t[1:-1] - t[:-2]) / np.where(span > 0, span, 1.0), 0.0)
        ex, ey, ez = _miss(x, frac), _miss(y, frac), _miss(z, frac)
        error_m = np.sqrt(ex * ex + ey * ey + ez * ez)
        dyaw = np.abs((_miss(yaw, frac) + 180.0) % 360.0 - 180.0)
        yaw_wraps = np.abs(yaw[2:] - yaw[:-2]) > 180.0
        droppable = (error_m <= TOLERANCE_M) & (dyaw <= TOLERANCE_DEG) & ~yaw_wraps
        # Drop only every other candidate per pass, so each is judged on neighbours that stay.
        candidates = np.flatnonzero(droppable) + 1
        candidates = candidates[candidates % 2 == parity % 2]
        if candidates.size == 0:
            if parity % 2 == 1 and not droppable.any():
                break
            continue
        index = np.delete(index, candidates)
    return rows[index]


def _miss(column: np.ndarray, frac: np.ndarray) -> np.ndarray:
    """Each inner value's interpolation between its neighbours (at frac) less the value."""
    return column[:-2] + (column[2:] - column[:-2]) * frac - column[1:-1]


def _encode_rows(rows: np.ndarray, t0_s: float) -> dict[str, list[int]]:
    q = rows.copy()
    q[:, 0] -= t0_s
    q[:, 4] %= 360.0
    ints = np.rint(q * _SCALE).astype(np.int64)
    deltas = np.diff(ints, axis=0, prepend=np.zeros((1, ints.shape[1]), dtype=np.int64))
    return {name: deltas[:, c].tolist() for c, name in enumerate(_COLUMNS)}


def decode_paths(paths: Mapping[str, Mapping[str, Sequence[int]]], t0_s: float
                 ) -> dict[str, np.ndarray]:
    """The stored paths back as (M, 6) arrays of t_s, x_m, y_m, z_m, yaw_deg, battery_pct."""
    out: dict[str, np.ndarray] = {}
    for drone, columns in paths.items():
        ints = np.column_stack([np.cumsum(np.asarray(columns[c], dtype=np.int64))
                                for c in _COLUMNS])
        rows = ints / _SCALE
        rows[:, 0] += t0_s
        out[drone] = rows
    return out


def _plain(value: Any) -> Any:
    """An event's value as JSON: texts cut, floats rounded, nested (frozen) objects and
    sequences made plain (a link_faults event holds its profiles as objects)."""
    if isinstance(value, str) and len(value) > _MAX_TEXT:
        return value[:_MAX_TEXT] + "..."
    if isinstance(value, float):
        return round(value, 2)
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value


def _event_json(t_s: float, vehicle: str, kind: str, data: Mapping[str, Any]) -> list[Any]:
    return [round(t_s, 2), vehicle, kind, {key: _plain(value) for key, value in data.items()}]


def encode_window(history: TruthHistory, t0_s: float | None = None,
                  t1_s: float | None = None, calls: Sequence[Mapping[str, Any]] = ()
                  ) -> dict[str, Any]:
    """The replay of [t0_s, t1_s] of `history` (default: all of it), with tool calls."""
    start = 0.0 if t0_s is None else float(t0_s)
    end = history.end_t_s if t1_s is None else float(t1_s)
    if t0_s is None:
        firsts = [history.trajectory(v)[:1, 0] for v in history.vehicle_ids]
        found = [float(f[0]) for f in firsts if f.size]
        start = min(found) if found else 0.0
    if math.isnan(end):
        end = start
    paths = {}
    for vehicle in history.vehicle_ids:
        rows = history.trajectory(vehicle, start, end)
        if rows.shape[0]:
            paths[vehicle] = _encode_rows(thin_rows(rows), start)
    events = [_event_json(e.t_s, e.vehicle_id, e.kind, e.data)
              for e in history.events(t0_s=start, t1_s=end)]
    return {"format": FORMAT, "t0_s": round(start, 3), "t1_s": round(end, 3), "paths": paths,
            "events": events, "calls": [dict(c) for c in calls]}


def write_json_gz(path: Path, data: Any) -> Path:
    """Write `data` as gzipped JSON (through a temporary file, then renamed)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    temp = path.with_name(f".{path.name}.tmp")
    text = json.dumps(data, separators=(",", ":"), allow_nan=False)
    temp.write_bytes(gzip.compress(text.encode("utf-8"), compresslevel=6, mtime=0))
    temp.replace(path)
    return path


def read_json_gz(path: Path) -> Any:
    return json.loads(gzip.decompress(path.read_bytes()).decode("utf-8"))


def _safe(part: str) -> str:
    return _SAFE.sub("_", part)


def world_path(results_dir: Path, session_id: str) -> Path:
    return results_dir / "replay" / _safe(session_id) / "world.json.gz"


def replay_path(results_dir: Path, session_id: str, task_id: str, agent: str,
                trial: int) -> Path:
    return (results_dir / "replay" / _safe(session_id)
            / f"{_safe(task_id)}.{_safe(agent)}.{int(trial)}.json.gz")


def session_world(data: Mapping[str, Any]) -> dict[str, Any]:
    """A session file's world part (no tasks, no hidden checks or plans)."""
    keep = ("id", "name", "family", "level", "map_size_m", "safety_margin_m", "environment",
            "drones", "targets", "obstacles")
    return {k: data[k] for k in keep if k in data}


def write_task_replay(results_dir: Path, record: Mapping[str, Any],
                      replay: Mapping[str, Any], world: Mapping[str, Any] | None) -> Path:
    """Store one task's replay (and, once per session, its world) under `results_dir`."""
    session = str(record["session"])
    if world is not None and not world_path(results_dir, session).exists():
        write_json_gz(world_path(results_dir, session), dict(world))
    return write_json_gz(replay_path(results_dir, session, str(record["task"]),
                                     str(record["agent"]), int(record.get("trial", 0))),
                         dict(replay))
