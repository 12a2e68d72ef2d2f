"""Ground-truth history of the emulated world, read only by validators.

:meth:`TruthRecorder.record_step` runs once per physics step with arrays for every vehicle. A
row ``(t_s, x_m, y_m, z_m, yaw_deg, battery_pct)`` is stored for a vehicle on the first step,
on every step it moves, on the step it stops (its resting sample), and for every vehicle on
each keyframe tick: the first step at or after ``first_t_s + k * keyframe_s`` (k = 1, 2, ...),
so a resting vehicle's battery drain shows. Rows are staged with fixed numpy work per step and
moved to per-vehicle chunk lists in batches; a query joins a vehicle's chunks into one array.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import tempfile
from abc import ABC, abstractmethod
from collections import Counter
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from emulator.truth_events import TruthEventKind

__all__ = ["TRAJECTORY_COLUMNS", "TargetRows", "TruthEvent", "TruthHistory", "TruthLog",
           "TruthRecorder"]

FORMAT_VERSION = 1
TRAJECTORY_COLUMNS: tuple[str, ...] = ("t_s", "x_m", "y_m", "z_m", "yaw_deg", "battery_pct")

_N_COLS = len(TRAJECTORY_COLUMNS)
_KEYFRAME_TOLERANCE_S = 1e-9
_MIN_STAGE_ROWS = 4096
_STAGE_ROWS_PER_VEHICLE = 64
_FIRST_CHUNK_ROWS = 64
_MAX_CHUNK_ROWS = 4096


def _json_default(value: Any) -> Any:
    if isinstance(value, np.ndarray | np.generic):
        return value.tolist()
    if isinstance(value, Mapping):
        return dict(value)
    raise TypeError(f"event data value of type {type(value).__name__} is not JSON-serialisable")


def _freeze(value: Any) -> Any:
    if isinstance(value, dict):
        return MappingProxyType({key: _freeze(item) for key, item in value.items()})
    if isinstance(value, list):
        return tuple(_freeze(item) for item in value)
    return value


def _read_only_rows(rows: npt.ArrayLike) -> np.ndarray:
    array = np.array(rows, dtype=np.float64).reshape(-1, _N_COLS)
    if np.any(np.diff(array[:, 0]) < 0.0):
        raise ValueError("trajectory rows are not sorted by time")
    array.setflags(write=False)
    return array


def _as_time(value: float | None, name: str, default: float) -> float:
    t = default if value is None else float(value)
    if math.isnan(t):
        raise ValueError(f"{name} must be a number, got {value!r}")
    return t


@dataclass(frozen=True, slots=True)
class TruthEvent:
    """Something that happened to one vehicle at one instant; ``data`` is read-only JSON."""

    t_s: float
    vehicle_id: str
    kind: TruthEventKind  # given as its word (a str), it becomes the member
    data: Mapping[str, Any]

    def __post_init__(self) -> None:
        if not math.isfinite(self.t_s):
            raise ValueError(f"event t_s must be finite, got {self.t_s!r}")
        if not isinstance(self.vehicle_id, str) or not self.vehicle_id:
            raise ValueError(f"event vehicle_id must be a non-empty string, "
                             f"got {self.vehicle_id!r}")
        try:
            object.__setattr__(self, "kind", TruthEventKind(self.kind))
        except ValueError:
            raise ValueError(f"event kind must be a truth event kind "
                             f"({', '.join(TruthEventKind)}), got {self.kind!r}") from None
        try:
            plain = json.loads(json.dumps(dict(self.data), default=_json_default))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"event {self.kind!r} data is not JSON-serialisable: {exc}") from exc
        object.__setattr__(self, "t_s", float(self.t_s))
        object.__setattr__(self, "data", _freeze(plain))

    def to_json(self) -> dict[str, Any]:
        """Plain JSON-ready form; ``TruthEvent(**event.to_json())`` rebuilds the event."""
        data = json.loads(json.dumps(self.data, default=_json_default))
        return {"t_s": self.t_s, "vehicle_id": self.vehicle_id, "kind": self.kind, "data": data}


class TargetRows(Protocol):
    """What records moving targets: their ids and exact (t, x, y, z) rows over a window."""

    ids: tuple[str, ...]

    def rows(self, target_id: str, t0_s: float, t1_s: float) -> np.ndarray: ...


class TruthHistory(ABC):
    """Queries shared by the live :class:`TruthRecorder` and a loaded :class:`TruthLog`."""

    def __init__(self, vehicle_ids: Sequence[str], keyframe_s: float) -> None:
        if isinstance(vehicle_ids, str):
            raise TypeError("vehicle_ids must be a sequence of ids, not a single string")
        ids = tuple(vehicle_ids)
        if bad := [v for v in ids if not isinstance(v, str) or not v]:
            raise ValueError(f"vehicle ids must be non-empty strings, got {bad!r}")
        if duplicates := sorted(v for v, count in Counter(ids).items() if count > 1):
            raise ValueError(f"duplicate vehicle ids: {', '.join(duplicates)}")
        if not (math.isfinite(keyframe_s) and keyframe_s > 0.0):
            raise ValueError(f"keyframe_s must be a positive finite number, got {keyframe_s!r}")
        self.vehicle_ids: tuple[str, ...] = ids
        self.keyframe_s: float = float(keyframe_s)
        self._index_of: dict[str, int] = {v: i for i, v in enumerate(ids)}
        self._events: list[TruthEvent] = []
        self._events_by_vehicle: list[list[TruthEvent]] = [[] for _ in ids]

    @property
    @abstractmethod
    def end_t_s(self) -> float:
        """Time of the latest recorded step; NaN when no step was recorded."""

    @property
    def moving_target_ids(self) -> tuple[str, ...]:
        """Ids of the moving targets whose trajectories are recorded."""
        return ()

    def _target_rows(self, target_id: str, t0_s: float, t1_s: float) -> np.ndarray:
        raise KeyError(f"no trajectory of target {target_id!r} is recorded")

    def target_trajectory(self, target_id: str, t0_s: float | None = None,
                          t1_s: float | None = None) -> np.ndarray:
        """Rows (t_s, x_m, y_m, z_m) of a moving target over [t0_s, t1_s] (clipped to what was
        recorded): both ends and every change of its velocity between, so that linear
        interpolation between rows is its exact motion. KeyError for an unrecorded target."""
        if target_id not in self.moving_target_ids:
            raise KeyError(f"no trajectory of target {target_id!r} is recorded")
        end = self.end_t_s
        if math.isnan(end):
            return np.zeros((0, 4))
        t0 = max(_as_time(t0_s, "t0_s", 0.0), 0.0)
        t1 = min(_as_time(t1_s, "t1_s", end), end)
        if t1 < t0:
            return np.zeros((0, 4))
        return self._target_rows(target_id, t0, t1)

    @abstractmethod
    def _samples(self, index: int) -> np.ndarray:
        """Every row of vehicle ``index`` as an (M, 6) float64 array sorted by t; do not modify."""

    @property
    def stored_rows(self) -> int:
        """Total trajectory rows held for all vehicles."""
        return sum(self._samples(i).shape[0] for i in range(len(self.vehicle_ids)))

    def _vehicle_index(self, vehicle_id: str) -> int:
        try:
            return self._index_of[vehicle_id]
        except KeyError:
            known = ", ".join(self.vehicle_ids) or "(none)"
            raise KeyError(f"unknown vehicle {vehicle_id!r}; known vehicles: {known}") from None

    def _add_event(self, event: TruthEvent) -> None:
        """Events are kept in (time, vehicle) order: events of different vehicles at the same
        instant (clients acting side by side) read the same whatever order they came in."""
        index = self._vehicle_index(event.vehicle_id)
        self._events_by_vehicle[index].append(event)
        events = self._events
        at = len(events)
        while at > 0 and events[at - 1].t_s == event.t_s and \
                self._vehicle_index(events[at - 1].vehicle_id) > index:
            at -= 1
        events.insert(at, event)

    def trajectory(
        self, vehicle_id: str, t0_s: float | None = None, t1_s: float | None = None
    ) -> np.ndarray:
        """Rows (t_s, x_m, y_m, z_m, yaw_deg, battery_pct) as a new (M, 6) float64 array.

        With ``t0_s`` the first row is the last sample at or before ``t0_s`` re-stamped to
        ``t0_s`` (when one exists), followed by every sample in ``(t0_s, t1_s]``.
        """
        rows = self._samples(self._vehicle_index(vehicle_id))
        t0 = _as_time(t0_s, "t0_s", -math.inf)
        t1 = _as_time(t1_s, "t1_s", math.inf)
        if t1 < t0:
            raise ValueError(f"empty window: t1_s={t1} is before t0_s={t0}")
        times = rows[:, 0]
        stop = int(np.searchsorted(times, t1, side="right"))
        first_after = int(np.searchsorted(times, t0, side="right"))
        if t0_s is None or first_after == 0:
            return rows[:stop].copy()
        window = rows[first_after - 1 : stop].copy()
        window[0, 0] = t0
        return window

    def position_at(self, vehicle_id: str, t_s: float) -> tuple[float, float, float]:
        """ENU position interpolated linearly between samples, clamped to the first/last one."""
        rows = self._samples(self._vehicle_index(vehicle_id))
        if rows.shape[0] == 0:
            raise ValueError(f"no samples recorded for vehicle {vehicle_id!r}")
        t = _as_time(t_s, "t_s", math.nan)
        after = int(np.searchsorted(rows[:, 0], t, side="right"))
        if after == 0:
            xyz = rows[0, 1:4]
        elif after == rows.shape[0]:
            xyz = rows[-1, 1:4]
        else:
            lo, hi = rows[after - 1], rows[after]
            fraction = (t - lo[0]) / (hi[0] - lo[0])
            xyz = lo[1:4] + fraction * (hi[1:4] - lo[1:4])
        return (float(xyz[0]), float(xyz[1]), float(xyz[2]))

    def events(
        self,
        vehicle_id: str | None = None,
        t0_s: float | None = None,
        t1_s: float | None = None,
        kinds: Iterable[str] | None = None,
    ) -> list[TruthEvent]:
        """Events in recording order, filtered by vehicle, ``t0_s <= t_s <= t1_s`` and kind."""
        t0 = _as_time(t0_s, "t0_s", -math.inf)
        t1 = _as_time(t1_s, "t1_s", math.inf)
        if isinstance(kinds, str):
            kinds = (kinds,)
        wanted = None if kinds is None else frozenset(kinds)
        index = None if vehicle_id is None else self._vehicle_index(vehicle_id)
        candidates = self._events if index is None else self._events_by_vehicle[index]
        return [e for e in candidates if t0 <= e.t_s <= t1 and (wanted is None or e.kind in wanted)]

    def export(self, path: str | Path, attachments: Mapping[str, str] | None = None) -> Path:
        """Write the whole history to one compressed ``.npz`` file, atomically; each of
        `attachments` (name -> text, e.g. the scenario as JSON) is stored beside it and read
        back with :meth:`TruthLog.attachment`."""
        target = Path(path)
        target.parent.mkdir(parents=True, exist_ok=True)
        arrays: dict[str, Any] = {
            f"trajectory_{i:05d}": self._samples(i) for i in range(len(self.vehicle_ids))
        }
        end_t_s = None if math.isnan(self.end_t_s) else self.end_t_s
        meta: dict[str, Any] = {"vehicle_ids": list(self.vehicle_ids), "end_t_s": end_t_s}
        meta.update(columns=list(TRAJECTORY_COLUMNS), keyframe_s=self.keyframe_s)
        targets = self.moving_target_ids
        if targets and end_t_s is not None:
            meta["moving_target_ids"] = list(targets)
            for i, target_id in enumerate(targets):
                arrays[f"target_{i:05d}"] = self.target_trajectory(target_id)
        arrays["meta_json"] = np.str_(json.dumps(meta))
        arrays["events_json"] = np.str_(json.dumps([e.to_json() for e in self._events]))
        arrays["format_version"] = np.array(FORMAT_VERSION)
        for name, text in (attachments or {}).items():
            arrays[f"attachment_{name}"] = np.str_(text)
        fd, temp_name = tempfile.mkstemp(prefix=f".{target.name}.", dir=target.parent)
        try:
            with os.fdopen(fd, "wb") as handle:
                np.savez_compressed(handle, **arrays)
                handle.flush()
                os.fsync(handle.fileno())
            os.replace(temp_name, target)
        except BaseException:
            with contextlib.suppress(FileNotFoundError):
                os.unlink(temp_name)
            raise
        return target


class TruthLog(TruthHistory):
    """Read-only truth history, e.g. loaded from an exported file."""

    def __init__(
        self,
        vehicle_ids: Sequence[str],
        trajectories: Sequence[npt.ArrayLike],
        events: Iterable[TruthEvent] = (),
        *,
        end_t_s: float = math.nan,
        keyframe_s: float = 1.0,
        target_trajectories: Mapping[str, npt.ArrayLike] | None = None,
    ) -> None:
        super().__init__(vehicle_ids, keyframe_s)
        if len(trajectories) != len(self.vehicle_ids):
            raise ValueError(f"{len(trajectories)} trajectories for {len(self.vehicle_ids)} ids")
        self._trajectories = tuple(_read_only_rows(rows) for rows in trajectories)
        for event in events:
            self._add_event(event)
        self._end_t_s = float(end_t_s)
        self._targets = {k: np.array(v, dtype=np.float64).reshape(-1, 4)
                         for k, v in (target_trajectories or {}).items()}

    @property
    def end_t_s(self) -> float:
        return self._end_t_s

    @property
    def moving_target_ids(self) -> tuple[str, ...]:
        return tuple(self._targets)

    def _target_rows(self, target_id: str, t0_s: float, t1_s: float) -> np.ndarray:
        rows = self._targets[target_id]
        if rows.shape[0] == 0:
            return rows.copy()
        inner = rows[(rows[:, 0] > t0_s) & (rows[:, 0] < t1_s)]
        ends = np.array([t0_s, t1_s]) if t1_s > t0_s else np.array([t0_s])
        xyz = np.column_stack([np.interp(ends, rows[:, 0], rows[:, c]) for c in (1, 2, 3)])
        out = np.vstack((np.column_stack((ends[:1], xyz[:1])), inner,
                         np.column_stack((ends[1:], xyz[1:]))))
        return out

    def _samples(self, index: int) -> np.ndarray:
        return self._trajectories[index]

    @staticmethod
    def attachment(path: str | Path, name: str) -> str | None:
        """The text attached as `name` when the file was exported; None when there is none."""
        with np.load(Path(path), allow_pickle=False) as archive:
            key = f"attachment_{name}"
            return str(archive[key]) if key in archive else None

    @classmethod
    def load(cls, path: str | Path) -> TruthLog:
        """Read a file written by :meth:`TruthHistory.export`."""
        with np.load(Path(path), allow_pickle=False) as archive:
            version = int(archive["format_version"]) if "format_version" in archive else None
            if version != FORMAT_VERSION:
                raise ValueError(f"{path}: truth log format {version}, expected {FORMAT_VERSION}")
            meta = json.loads(str(archive["meta_json"]))
            ids = meta["vehicle_ids"]
            trajectories = [archive[f"trajectory_{i:05d}"] for i in range(len(ids))]
            events = [TruthEvent(**e) for e in json.loads(str(archive["events_json"]))]
            targets = {t: archive[f"target_{i:05d}"]
                       for i, t in enumerate(meta.get("moving_target_ids", []))}
        end_t_s = math.nan if meta["end_t_s"] is None else meta["end_t_s"]
        return cls(ids, trajectories, events, end_t_s=end_t_s, keyframe_s=meta["keyframe_s"],
                   target_trajectories=targets)


class TruthRecorder(TruthHistory):
    """Records every vehicle's trajectory at physics-step resolution, plus events."""

    def __init__(self, vehicle_ids: Sequence[str], *, keyframe_s: float = 1.0) -> None:
        super().__init__(vehicle_ids, keyframe_s)
        n = len(self.vehicle_ids)
        self._n = n
        self._all_index = np.arange(n, dtype=np.intp)
        self._shapes = ((n, 3), (n,), (n,), (n,))
        self._was_moving = np.zeros(n, dtype=bool)
        stage_rows = max(_MIN_STAGE_ROWS, _STAGE_ROWS_PER_VEHICLE * n)
        self._stage = np.empty((stage_rows, _N_COLS + 1), dtype=np.float64)
        self._stage_len = 0
        self._owner_dtype = np.uint16 if n <= 2**16 else np.intp
        self._chunks = [[np.empty((_FIRST_CHUNK_ROWS, _N_COLS))] for _ in range(n)]
        self._fill = [0] * n
        self._end_t_s = -math.inf
        self._first_t_s = math.nan
        self._next_keyframe_t_s = -math.inf
        self._moving: TargetRows | None = None
        self._left: np.ndarray | None = None  # vehicles no longer recorded (left the run)

    @property
    def end_t_s(self) -> float:
        return math.nan if self._end_t_s == -math.inf else self._end_t_s

    def attach_targets(self, moving: TargetRows) -> None:
        """Record the moving targets of `moving` too: their motion is decided by their start,
        so the recorder asks it for their exact rows up to the latest recorded step."""
        self._moving = moving

    @property
    def moving_target_ids(self) -> tuple[str, ...]:
        return () if self._moving is None else tuple(self._moving.ids)

    def _target_rows(self, target_id: str, t0_s: float, t1_s: float) -> np.ndarray:
        assert self._moving is not None
        return self._moving.rows(target_id, t0_s, t1_s)

    @property
    def nbytes(self) -> int:
        """Bytes held by the staging and per-vehicle buffers."""
        return self._stage.nbytes + sum(c.nbytes for chunks in self._chunks for c in chunks)

    def record_step(
        self,
        t_s: float,
        position_m: npt.ArrayLike,
        yaw_deg: npt.ArrayLike,
        battery_pct: npt.ArrayLike,
        moving: npt.ArrayLike,
    ) -> None:
        """Record one physics step: position_m (N, 3) ENU, yaw_deg, battery_pct, moving (N,)."""
        t = float(t_s)
        if not self._end_t_s <= t < math.inf:
            raise ValueError(
                f"t_s must be finite and non-decreasing: got {t_s!r} after {self.end_t_s!r}"
            )
        position_m = np.asarray(position_m)
        yaw_deg, battery_pct = np.asarray(yaw_deg), np.asarray(battery_pct)
        moving = np.asarray(moving, dtype=bool)
        shapes = (position_m.shape, yaw_deg.shape, battery_pct.shape, moving.shape)
        if shapes != self._shapes:
            raise ValueError(
                f"record_step expects shapes {self._shapes} for position_m, yaw_deg, "
                f"battery_pct, moving; got {shapes}"
            )
        self.record_fleet_step(t, position_m, yaw_deg, battery_pct, moving)

    def record_fleet_step(self, t_s: float, position_m: np.ndarray, yaw_deg: np.ndarray,
                          battery_pct: np.ndarray, moving: np.ndarray) -> None:
        """`record_step` without its checks, for the fleet's physics step: float t_s not
        before the last step, float arrays of the recorder's shapes and a bool mask."""
        if t_s >= self._next_keyframe_t_s:
            self._schedule_next_keyframe(t_s)
            index = self._all_index
        else:
            index = (moving | self._was_moving).nonzero()[0]
        np.copyto(self._was_moving, moving)
        self._end_t_s = t_s
        size = index.size
        if not size:
            return
        if self._stage_len + size > self._stage.shape[0]:
            self._flush()
        start = self._stage_len
        self._stage_len = end = start + size
        rows = self._stage[start:end]
        rows[:, 0] = t_s
        if size == self._n:
            rows[:, 1:4] = position_m
            rows[:, 4] = yaw_deg
            rows[:, 5] = battery_pct
        else:
            rows[:, 1:4] = position_m.take(index, 0)
            rows[:, 4] = yaw_deg.take(index)
            rows[:, 5] = battery_pct.take(index)
        rows[:, 6] = index

    def record_steps(self, t_s: np.ndarray, position_m: np.ndarray, yaw_deg: np.ndarray,
                     battery_pct: np.ndarray, moving: np.ndarray) -> None:
        """Record K consecutive steps at once, with the same rows `record_step` would store.

        t_s (K,) increasing, position_m (K, N, 3), battery_pct (K, N); yaw_deg (N,) and the
        moving mask (N,) are constant over the K steps (steady flight).
        """
        t_s = np.asarray(t_s, dtype=float)
        count = t_s.shape[0]
        if count == 0:
            return
        if not (self._end_t_s <= t_s[0] and np.all(np.diff(t_s) >= 0) and np.isfinite(t_s[-1])):
            raise ValueError("t_s must be finite and non-decreasing")
        self.record_fleet_steps(t_s, np.asarray(position_m), np.asarray(yaw_deg),
                                np.asarray(battery_pct), np.asarray(moving, dtype=bool))

    def record_fleet_steps(self, t_s: np.ndarray, position_m: np.ndarray, yaw_deg: np.ndarray,
                           battery_pct: np.ndarray, moving: np.ndarray) -> None:
        """`record_steps` without its checks, for the fleet's fast-forward: float times not
        before the last step and increasing, arrays of the documented shapes; yaw_deg and
        moving may also be given per step, (K, N)."""
        count = t_s.shape[0]
        # Steps that carry a keyframe (every vehicle) instead of only the moving ones.
        keyframe = None
        if t_s[-1] >= self._next_keyframe_t_s:
            keyframe = np.zeros(count, dtype=bool)
            k = 0
            while k < count:
                if t_s[k] >= self._next_keyframe_t_s:
                    keyframe[k] = True
                    self._schedule_next_keyframe(float(t_s[k]))
                    k += 1
                else:
                    k = int(np.searchsorted(t_s, self._next_keyframe_t_s, side="left"))
        self._end_t_s = float(t_s[-1])
        last = moving[-1] if moving.ndim == 2 else moving
        if np.count_nonzero(moving) == moving.size:  # every vehicle moves: every row stored
            np.copyto(self._was_moving, last)
            rows = self._new_rows(count * self._n)
            grid = rows.reshape(count, self._n, _N_COLS + 1)
            grid[:, :, 0] = t_s[:, None]
            grid[:, :, 1:4] = position_m
            grid[:, :, 4] = yaw_deg
            grid[:, :, 5] = battery_pct
            grid[:, :, 6] = self._all_index
            self._staged(rows)
            return
        # Which vehicles each step stores: all on a keyframe, else the moving ones (and on
        # the first step those that stopped moving with the step before).
        stored = np.empty((count, self._n), dtype=bool)
        stored[:] = moving
        if moving.ndim == 2:  # per step: also the step after a vehicle stopped moving
            stored[1:] |= moving[:-1]
        stored[0] |= self._was_moving
        if keyframe is not None:
            stored[keyframe] = True if self._left is None else ~self._left
        np.copyto(self._was_moving, last)
        steps, index = stored.nonzero()
        if not index.size:
            return
        rows = self._new_rows(index.size)
        rows[:, 0] = t_s[steps]
        rows[:, 1:4] = position_m[steps, index]
        rows[:, 4] = yaw_deg[steps, index] if yaw_deg.ndim == 2 else yaw_deg[index]
        rows[:, 5] = battery_pct[steps, index]
        rows[:, 6] = index
        self._staged(rows)

    def _new_rows(self, size: int) -> np.ndarray:
        """`size` rows to fill and hand to `_staged`: the next rows of the stage, or an array
        of their own when the stage cannot hold them."""
        if self._stage_len + size > self._stage.shape[0]:
            self._flush()
        if size > self._stage.shape[0]:
            return np.empty((size, _N_COLS + 1))
        start = self._stage_len
        self._stage_len = start + size
        return self._stage[start : self._stage_len]

    def _staged(self, rows: np.ndarray) -> None:
        """The rows of `_new_rows` are filled in."""
        if rows.base is not self._stage:
            self._group_into_chunks(rows)

    def add_vehicle(self, vehicle_id: str, t_s: float, position_m: npt.ArrayLike,
                    yaw_deg: float, battery_pct: float) -> int:
        """Record a vehicle that joins the run at t_s (the latest recorded step) from its first
        row on; returns its index. ValueError for an id recorded before (a left one too)."""
        if not isinstance(vehicle_id, str) or not vehicle_id:
            raise ValueError("a vehicle id is a non-empty string")
        if vehicle_id in self._index_of:
            raise ValueError(f"vehicle {vehicle_id!r} is already recorded in this run")
        if self._stage_len:
            self._flush()
        k = self._n
        self.vehicle_ids = (*self.vehicle_ids, vehicle_id)
        self._index_of[vehicle_id] = k
        self._events_by_vehicle.append([])
        self._n = n = k + 1
        self._shapes = ((n, 3), (n,), (n,), (n,))
        self._was_moving = np.append(self._was_moving, False)
        self._chunks.append([np.empty((_FIRST_CHUNK_ROWS, _N_COLS))])
        self._fill.append(0)
        if self._left is not None:
            self._left = np.append(self._left, False)
        self._all_index = np.arange(n, dtype=np.intp) if self._left is None else \
            (~self._left).nonzero()[0]
        x, y, z = (float(v) for v in np.asarray(position_m, dtype=float))
        self._append(k, np.array([[float(t_s), x, y, z, float(yaw_deg), float(battery_pct)]]))
        return k

    def retire(self, vehicle_id: str) -> None:
        """Stop recording a vehicle that left the run: its history ends at the latest
        recorded step and stays queryable."""
        k = self._vehicle_index(vehicle_id)
        if self._left is None:
            self._left = np.zeros(self._n, dtype=bool)
        self._left[k] = True
        self._was_moving[k] = False
        self._all_index = (~self._left).nonzero()[0]

    def record_event(self, t_s: float, vehicle_id: str, kind: TruthEventKind, **data: Any
                     ) -> TruthEvent:
        """Record an event for a known vehicle; ``data`` must be JSON-serialisable."""
        event = TruthEvent(t_s=float(t_s), vehicle_id=vehicle_id, kind=kind, data=data)
        self._add_event(event)
        return event

    def snapshot(self) -> TruthLog:
        """An independent read-only copy of everything recorded so far."""
        ids, rows = self.vehicle_ids, [self._samples(i) for i in range(self._n)]
        targets = {t: self.target_trajectory(t) for t in self.moving_target_ids}
        return TruthLog(ids, rows, self._events, end_t_s=self.end_t_s, keyframe_s=self.keyframe_s,
                        target_trajectories=targets)

    @classmethod
    def load(cls, path: str | Path) -> TruthLog:
        """Read an exported history as a read-only :class:`TruthLog`."""
        return TruthLog.load(path)

    def _schedule_next_keyframe(self, t: float) -> None:
        if math.isnan(self._first_t_s):
            self._first_t_s = t
        elapsed_s = t - self._first_t_s + _KEYFRAME_TOLERANCE_S
        ticks_done = math.floor(elapsed_s / self.keyframe_s)
        next_tick_s = self._first_t_s + (ticks_done + 1) * self.keyframe_s
        self._next_keyframe_t_s = next_tick_s - _KEYFRAME_TOLERANCE_S

    def _samples(self, index: int) -> np.ndarray:
        if self._stage_len:
            self._flush()
        chunks, fill = self._chunks[index], self._fill[index]
        if len(chunks) > 1:
            chunks[:] = [np.concatenate([*chunks[:-1], chunks[-1][:fill]])]
            fill = self._fill[index] = chunks[0].shape[0]
        return chunks[0][:fill]

    def _flush(self) -> None:
        self._group_into_chunks(self._stage[: self._stage_len])
        self._stage_len = 0

    def _group_into_chunks(self, staged: np.ndarray) -> None:
        owners = staged[:, _N_COLS].astype(self._owner_dtype)
        grouped = staged[np.argsort(owners, kind="stable"), :_N_COLS]
        counts = np.bincount(owners, minlength=self._n).tolist()
        start = 0
        for vehicle, count in enumerate(counts):
            if count:
                self._append(vehicle, grouped[start : start + count])
                start += count

    def _append(self, vehicle: int, rows: np.ndarray) -> None:
        chunks, fill = self._chunks[vehicle], self._fill[vehicle]
        last = chunks[-1]
        room = last.shape[0] - fill
        if rows.shape[0] <= room:
            last[fill : fill + rows.shape[0]] = rows
            self._fill[vehicle] = fill + rows.shape[0]
            return
        last[fill:], rest = rows[:room], rows[room:]
        size = max(rest.shape[0], min(2 * last.shape[0], _MAX_CHUNK_ROWS))
        chunks.append(np.empty((size, _N_COLS), dtype=np.float64))
        chunks[-1][: rest.shape[0]] = rest
        self._fill[vehicle] = rest.shape[0]
