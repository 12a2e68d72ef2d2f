"""Ground-truth recording of the emulated world, read only by validators.

:meth:`TruthRecorder.record_step` runs once per physics step with arrays for every vehicle. A
row ``(t_s, x_m, y_m, z_m, yaw_deg, battery_pct)`` is stored for a vehicle on the first step,
on every step it moves, on the step it stops (its resting sample), and for every vehicle on
each keyframe tick: the first step at or after ``first_t_s + k * keyframe_s`` (k = 1, 2, ...),
so a resting vehicle's battery drain shows. Rows are staged with fixed numpy work per step and
moved to per-vehicle chunk lists in batches; a query joins a vehicle's chunks into one array.
The history it shares with a saved file (`TruthLog`) is in `emulator.truth_history`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from emulator.truth_events import TruthEventKind
from emulator.truth_history import (
    TRAJECTORY_COLUMNS,
    TargetRows,
    TruthEvent,
    TruthHistory,
    TruthLog,
)

__all__ = ["TRAJECTORY_COLUMNS", "TargetRows", "TruthEvent", "TruthHistory", "TruthLog",
           "TruthRecorder"]

_N_COLS = len(TRAJECTORY_COLUMNS)
_KEYFRAME_TOLERANCE_S = 1e-9
_MIN_STAGE_ROWS = 4096
_STAGE_ROWS_PER_VEHICLE = 64
_FIRST_CHUNK_ROWS = 64
_MAX_CHUNK_ROWS = 4096


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
        # Whether every staged row so far belongs to a block of the whole fleet in vehicle
        # order (the usual case): such a stage is split by vehicle without sorting.
        self._stage_regular = True
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
        if size != self._n or self._left is not None:
            self._stage_regular = False
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
            self._staged(rows, regular=self._left is None)
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
        self._staged(rows, regular=False)

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

    def _staged(self, rows: np.ndarray, *, regular: bool) -> None:
        """The rows of `_new_rows` are filled in (`regular`: blocks of the whole fleet in
        vehicle order)."""
        if rows.base is not self._stage:
            self._group_into_chunks(rows, regular=regular)
        elif not regular:
            self._stage_regular = False

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
            # One chunk again, with room for the rows to come: the next read is a view, not
            # a copy of the whole history.
            parts = [*chunks[:-1], chunks[-1][:fill]]
            total = sum(part.shape[0] for part in parts)
            room = min(max(total // 2, _FIRST_CHUNK_ROWS), _MAX_CHUNK_ROWS)
            whole = np.empty((total + room, _N_COLS))
            np.concatenate(parts, out=whole[:total])
            chunks[:] = [whole]
            fill = self._fill[index] = total
        return chunks[0][:fill]

    def _flush(self) -> None:
        self._group_into_chunks(self._stage[: self._stage_len], regular=self._stage_regular)
        self._stage_len = 0
        self._stage_regular = True

    def _group_into_chunks(self, staged: np.ndarray, *, regular: bool) -> None:
        if regular and staged.shape[0]:  # whole-fleet blocks: vehicle k's rows are every n-th
            blocks = staged.reshape(-1, self._n, _N_COLS + 1)
            for vehicle in range(self._n):
                self._append(vehicle, blocks[:, vehicle, :_N_COLS])
            return
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
