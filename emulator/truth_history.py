"""Ground-truth history of the emulated world as validators read it: the events, the
trajectory rows of every vehicle and moving target, and the saved file (`TruthLog`).

A trajectory row is ``(t_s, x_m, y_m, z_m, yaw_deg, battery_pct)``; `emulator.truth` records
them while the world runs (`TruthRecorder`), and both read them back through `TruthHistory`.
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

__all__ = ["TRAJECTORY_COLUMNS", "TargetRows", "TruthEvent", "TruthHistory", "TruthLog"]

FORMAT_VERSION = 1
TRAJECTORY_COLUMNS: tuple[str, ...] = ("t_s", "x_m", "y_m", "z_m", "yaw_deg", "battery_pct")

_N_COLS = len(TRAJECTORY_COLUMNS)


def _json_default(value: Any) -> Any:
    if isinstance(value, np.ndarray | np.generic):
        return value.tolist()
    if isinstance(value, Mapping):
        return dict(value)
    raise TypeError(f"event data value of type {type(value).__name__} is not JSON-serialisable")


_SCALARS = frozenset((str, int, float, bool, type(None)))
_MAPPINGS = (dict, MappingProxyType)


def _flat(data: Mapping[str, Any]) -> bool:
    """Whether data is str keys to plain JSON scalars, which a JSON round trip gives back
    as they are (floats by their repr, NaN and the infinities included)."""
    return type(data) in _MAPPINGS and all(
        type(key) is str and type(value) in _SCALARS for key, value in data.items())


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
            plain = (dict(self.data) if _flat(self.data)
                     else json.loads(json.dumps(dict(self.data), default=_json_default)))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"event {self.kind!r} data is not JSON-serialisable: {exc}") from exc
        object.__setattr__(self, "t_s", float(self.t_s))
        object.__setattr__(self, "data", _freeze(plain))

    def to_json(self) -> dict[str, Any]:
        """Plain JSON-ready form; ``TruthEvent(**event.to_json())`` rebuilds the event."""
        data = (dict(self.data) if _flat(self.data)
                else json.loads(json.dumps(self.data, default=_json_default)))
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
