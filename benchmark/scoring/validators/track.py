"""A vehicle's ground-truth trajectory clipped exactly to a time window.

The recorder stores a row on every physics step while a vehicle moves and keyframes while it
rests, so the state between two rows is their linear interpolation. Operator resets
(``operator_place``, ``operator_battery``) change the state outside the flight model: each one
adds a row at the event time with the new state, and the segment leading to it is marked as
not joined (a jump that was never flown).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from emulator.truth import TruthHistory
from emulator.truth_events import TruthEventKind

__all__ = ["OPERATOR_EVENTS", "Track", "build_track"]

OPERATOR_EVENTS = (TruthEventKind.OPERATOR_PLACE, TruthEventKind.OPERATOR_BATTERY)
# Extra history read before a window, so the row at or before its start is a true sample
# (every vehicle gets a keyframe row at least every keyframe_s).
_PAD_KEYFRAMES = 2.0


@dataclass(frozen=True, slots=True)
class Track:
    """Contiguous columns t_s (n,), xyz_m (n, 3), xy_m (n, 2, a copy of the horizontal part),
    yaw_deg (n,), battery_pct (n,); joined (n - 1,) is False for a segment that is a reset jump
    rather than flight."""

    t_s: np.ndarray
    xyz_m: np.ndarray
    xy_m: np.ndarray
    yaw_deg: np.ndarray
    battery_pct: np.ndarray
    joined: np.ndarray

    @classmethod
    def from_rows(cls, rows: np.ndarray, joined: np.ndarray) -> Track:
        """A track from rows (n, 6) as in TRAJECTORY_COLUMNS; the arrays are read-only."""
        columns = (np.ascontiguousarray(rows[:, 0]), np.ascontiguousarray(rows[:, 1:4]),
                   np.ascontiguousarray(rows[:, 1:3]), np.ascontiguousarray(rows[:, 4]),
                   np.ascontiguousarray(rows[:, 5]),
                   np.array(joined, dtype=bool))
        for column in columns:
            column.setflags(write=False)
        return cls(*columns)

    @property
    def size(self) -> int:
        return int(self.t_s.shape[0])

    @property
    def empty(self) -> bool:
        return self.size == 0

    def segment_speeds_m_s(self) -> np.ndarray:
        """3D speed of every joined segment with a positive duration."""
        if self.size < 2:
            return np.zeros(0)
        dt = np.diff(self.t_s)
        step = np.linalg.norm(np.diff(self.xyz_m, axis=0), axis=1)
        keep = self.joined & (dt > 1e-9)
        return step[keep] / dt[keep]

    def max_speed_m_s(self) -> float:
        speeds = self.segment_speeds_m_s()
        return float(speeds.max()) if speeds.size else 0.0

    def last_speed_m_s(self) -> float:
        """Speed over the last joined segment with a positive duration (0 when none)."""
        speeds = self.segment_speeds_m_s()
        return float(speeds[-1]) if speeds.size else 0.0


def _empty() -> Track:
    return Track.from_rows(np.zeros((0, 6)), np.zeros(0, dtype=bool))


def _insert_resets(history: TruthHistory, vehicle_id: str, rows: np.ndarray, a_s: float,
                   b_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Rows with one row added per operator reset, and the joined flag of each segment."""
    resets = history.events(vehicle_id, a_s, b_s, kinds=OPERATOR_EVENTS)
    joined = np.ones(max(rows.shape[0] - 1, 0), dtype=bool)
    for event in resets:
        k = int(np.searchsorted(rows[:, 0], event.t_s, side="right"))
        if rows.shape[0] == 0:
            continue
        base = rows[k - 1] if k > 0 else rows[0]
        new = base.copy()
        new[0] = event.t_s
        if event.kind is TruthEventKind.OPERATOR_PLACE:
            new[1:4] = [float(v) for v in event.data["position_m"]]
        else:
            new[5] = float(event.data["battery_pct"])
        rows = np.insert(rows, k, new, axis=0)
        # Segment k-1 -> k is the jump; k -> k+1 continues from the new state.
        if k == 0:
            joined = np.insert(joined, 0, True)
        else:
            joined = np.insert(joined, k - 1, False)
            if k < joined.shape[0]:
                joined[k] = True
    return rows, joined


def build_track(history: TruthHistory, vehicle_id: str, a_s: float, b_s: float) -> Track:
    """The vehicle's state over [a_s, b_s]: interpolated rows at both ends and every sample
    between. The last row is held up to min(b_s, history end) since a resting vehicle adds no
    rows. Empty when nothing was recorded at or before b_s."""
    pad = _PAD_KEYFRAMES * history.keyframe_s + 0.1
    rows = history.trajectory(vehicle_id, a_s - pad, b_s + pad)
    if rows.shape[0] == 0:
        return _empty()
    restamped = rows[0, 0] == a_s - pad
    sampled = rows.shape[0]
    rows, joined = _insert_resets(history, vehicle_id, rows, a_s - pad, b_s + pad)
    # Without resets, position_at gives the exact position where the padded read has no
    # sample on one side (only in histories sparser than the keyframe period).
    exact = rows.shape[0] == sampled
    t = rows[:, 0]
    n = rows.shape[0]
    lo = int(np.searchsorted(t, a_s, side="right")) - 1
    hi = int(np.searchsorted(t, b_s, side="right")) - 1
    if hi < 0:
        return _empty()
    # rows is this call's own copy: the window's end rows are rewritten in place.
    first = max(lo, 0)
    if lo >= 0:
        start = _state_at(rows, joined, lo, a_s)
        if lo == 0 and restamped and exact:
            start[1:4] = history.position_at(vehicle_id, a_s)
        rows[lo] = start
    stop = hi + 1
    if b_s > rows[hi, 0]:
        if hi < n - 1 and joined[hi] and rows[hi + 1, 0] > rows[hi, 0]:
            end = _state_at(rows, joined, hi, b_s)
        else:
            hold_s = min(b_s, history.end_t_s) if math.isfinite(history.end_t_s) else b_s
            end = rows[hi].copy()
            end[0] = max(hold_s, rows[hi, 0])
            if hi == n - 1 and exact:
                end[1:4] = history.position_at(vehicle_id, end[0])
        if end[0] > rows[hi, 0]:
            if hi < n - 1:
                rows[hi + 1] = end
                joined[hi] = True
            else:
                rows = np.vstack((rows, end))
                joined = np.append(joined, True)
            stop = hi + 2
    return Track.from_rows(rows[first:stop], joined[first:stop - 1])


def _state_at(rows: np.ndarray, joined: np.ndarray, k: int, t_s: float) -> np.ndarray:
    """State at t_s, where row k is the last row at or before it."""
    row = rows[k].copy()
    if k + 1 < rows.shape[0] and joined[k]:
        nxt = rows[k + 1]
        span = nxt[0] - row[0]
        if span > 0.0 and t_s > row[0]:
            f = min((t_s - row[0]) / span, 1.0)
            row[1:4] += f * (nxt[1:4] - row[1:4])
            row[5] += f * (nxt[5] - row[5])
    row[0] = t_s
    return row
