"""Which parts of a drone's flight came within its task radius of a target.

The flight path of a drone in the window is its airborne trajectory as a polyline: each joined
pair of consecutive samples at z >= 1 m is a segment (a lone airborne sample is a zero-length
segment). A segment is *in range* of a target when its 2D distance to the target's footprint
is at most the drone's task radius, so a pass between two samples counts. A *visit* is a
maximal chain of connected in-range segments; its period runs from the start of its first
segment to the end of its last.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from benchmark.scoring.validators.context import AIRBORNE_M, CheckContext
from benchmark.scoring.validators.geometry import Footprint
from benchmark.scoring.validators.track import Track

__all__ = ["FlightPath", "Visit", "flight_path", "footprint", "target_rows", "visits"]

_BLOCK = 128
_EPS_M = 1e-9


@dataclass(frozen=True, slots=True)
class Visit:
    """One continuous period in range of a target."""

    start_s: float
    end_s: float

    @property
    def duration_s(self) -> float:
        return self.end_s - self.start_s


@dataclass(frozen=True, slots=True)
class FlightPath:
    """Airborne segments a[k] -> b[k] (xy) over [t0[k], t1[k]]; connected[k] says whether
    segment k + 1 starts where segment k ends."""

    a: np.ndarray
    b: np.ndarray
    t0: np.ndarray
    t1: np.ndarray
    connected: np.ndarray
    block_lo: np.ndarray
    block_hi: np.ndarray

    @property
    def size(self) -> int:
        return int(self.a.shape[0])

    @classmethod
    def from_track(cls, track: Track) -> FlightPath:
        n = track.size
        if n == 0:
            empty = np.zeros((0, 2))
            return cls(empty, empty, np.zeros(0), np.zeros(0), np.zeros(0, dtype=bool),
                       empty, empty)
        air = track.xyz_m[:, 2] >= AIRBORNE_M
        ok = track.joined & air[:-1] & air[1:]
        seg = np.flatnonzero(ok)
        covered = np.zeros(n, dtype=bool)
        covered[:-1] |= ok
        covered[1:] |= ok
        lone = np.flatnonzero(air & ~covered)
        if lone.size:
            i0 = np.concatenate((seg, lone))
            i1 = np.concatenate((seg + 1, lone))
            order = np.lexsort((i1, i0))
            i0, i1 = i0[order], i1[order]
        else:
            i0, i1 = seg, seg + 1
        xy = track.xy_m
        t = track.t_s
        if not lone.size and seg.size and seg[-1] - seg[0] + 1 == seg.size:
            # One unbroken flight: the segments are consecutive rows (views, no copies).
            first, stop = int(seg[0]), int(seg[-1]) + 1
            a, b = xy[first:stop], xy[first + 1:stop + 1]
            t0, t1 = t[first:stop], t[first + 1:stop + 1]
        else:
            a, b, t0, t1 = xy[i0], xy[i1], t[i0], t[i1]
        return cls.from_segments(a, b, t0, t1, i1[:-1] == i0[1:])

    def in_range(self, shape: Footprint, radius_m: float) -> np.ndarray:
        """Mask of segments whose distance to the footprint is <= radius_m."""
        mask = np.zeros(self.size, dtype=bool)
        if not self.size:
            return mask
        cx, cy = shape.center_xy
        gap_x = np.maximum(np.maximum(self.block_lo[:, 0] - cx, cx - self.block_hi[:, 0]), 0.0)
        gap_y = np.maximum(np.maximum(self.block_lo[:, 1] - cy, cy - self.block_hi[:, 1]), 0.0)
        near_blocks = np.flatnonzero(np.hypot(gap_x, gap_y) <= radius_m + shape.bound_radius_m
                                     + _EPS_M)
        if not near_blocks.size:
            return mask
        idx = (near_blocks[:, None] * _BLOCK + np.arange(_BLOCK)).ravel()
        idx = idx[idx < self.size]
        idx = idx[shape.lower_bound(self.a[idx], self.b[idx]) <= radius_m + _EPS_M]
        if idx.size:
            exact = shape.segment_distance(self.a[idx], self.b[idx]) <= radius_m + _EPS_M
            mask[idx[exact]] = True
        return mask

    def chains(self, mask: np.ndarray) -> list[tuple[int, int]]:
        """Maximal runs [first, last] of connected segments selected by mask."""
        k = np.flatnonzero(mask)
        if not k.size:
            return []
        new = np.ones(k.size, dtype=bool)
        new[1:] = (np.diff(k) != 1) | ~self.connected[k[1:] - 1]
        firsts = np.flatnonzero(new)
        lasts = np.append(firsts[1:] - 1, k.size - 1)
        return [(int(k[f]), int(k[e])) for f, e in zip(firsts, lasts, strict=True)]

    def relative_to(self, rows: np.ndarray) -> FlightPath:
        """The path as seen from a moving point whose exact motion is the linear
        interpolation of rows (t, x, y[, z]): each segment is cut where the point changes
        velocity, and every vertex is the drone's position less the point's at that instant.
        """
        if not self.size or rows.shape[0] == 0:
            return self
        times = rows[:, 0]
        lo = np.searchsorted(times, self.t0, side="right")
        hi = np.searchsorted(times, self.t1, side="left")
        cuts = np.maximum(hi - lo, 0)
        pieces = cuts + 1
        seg = np.repeat(np.arange(self.size), pieces)
        first = np.concatenate(([0], np.cumsum(pieces)[:-1]))
        rank = np.arange(seg.size) - np.repeat(first, pieces)
        # Start time of each piece: the segment start, then the cuts inside it.
        cut_index = np.repeat(lo, pieces) + rank - 1
        start_t = np.where(rank == 0, self.t0[seg], times[np.clip(cut_index, 0, None)])
        last = rank == pieces[seg] - 1
        end_t = np.where(last, self.t1[seg], times[np.clip(cut_index + 1, 0, times.size - 1)])
        span = self.t1[seg] - self.t0[seg]
        safe = np.where(span > 0.0, span, 1.0)

        def drone_at(t: np.ndarray) -> np.ndarray:
            f = np.where(span > 0.0, (t - self.t0[seg]) / safe, 0.0)[:, None]
            return self.a[seg] + f * (self.b[seg] - self.a[seg])

        def point_at(t: np.ndarray) -> np.ndarray:
            return np.column_stack([np.interp(t, times, rows[:, c]) for c in (1, 2)])

        a = drone_at(start_t) - point_at(start_t)
        b = drone_at(end_t) - point_at(end_t)
        connected = np.ones(seg.size - 1, dtype=bool) if seg.size > 1 else np.zeros(0, bool)
        boundary = np.flatnonzero(last[:-1])
        connected[boundary] = self.connected[seg[boundary]]
        return FlightPath.from_segments(a, b, start_t, end_t, connected)

    @classmethod
    def from_segments(cls, a: np.ndarray, b: np.ndarray, t0: np.ndarray, t1: np.ndarray,
                      connected: np.ndarray) -> FlightPath:
        starts = np.arange(0, a.shape[0], _BLOCK)
        if starts.size:
            block_lo = np.minimum.reduceat(np.minimum(a, b), starts, axis=0)
            block_hi = np.maximum.reduceat(np.maximum(a, b), starts, axis=0)
        else:
            block_lo = block_hi = np.zeros((0, 2))
        return cls(a, b, t0, t1, connected, block_lo, block_hi)

    def coordinates(self, first: int, last: int) -> np.ndarray:
        """Polyline vertices of the connected segments first..last."""
        return np.vstack((self.a[first:last + 1], self.b[last:last + 1]))


def flight_path(ctx: CheckContext, drone_id: str) -> FlightPath:
    """The drone's airborne flight path in the window (cached on the context)."""
    return ctx.cached(("flight", drone_id),
                      lambda: FlightPath.from_track(ctx.window(drone_id)))


def footprint(ctx: CheckContext, target_id: str) -> Footprint:
    """The target's footprint for distance queries (cached on the context); a moving target's
    is where it stands at the end of the window (current-state checks look at that instant).
    """
    def make() -> Footprint:
        shape = Footprint.of_target(ctx.target(target_id))
        rows = target_rows(ctx, target_id)
        if rows is None or rows.shape[0] == 0:
            return shape
        return Footprint((float(rows[-1, 1]), float(rows[-1, 2])), shape.bound_radius_m,
                         shape.disc_radius_m, None, None)
    return ctx.cached(("footprint", target_id), make)


def target_rows(ctx: CheckContext, target_id: str) -> np.ndarray | None:
    """A moving target's exact (t, x, y, z) rows over the window, or None for a target that
    does not move (or whose motion the ground truth does not hold)."""
    if target_id not in ctx.history.moving_target_ids:
        return None
    return ctx.cached(("target_rows", target_id),
                      lambda: ctx.history.target_trajectory(target_id, ctx.t0_s, ctx.t1_s))


def visits(ctx: CheckContext, drone_id: str, target_id: str) -> tuple[Visit, ...]:
    """The drone's separate visits to the target in the window, in time order. A moving
    target is met where it was at each instant: the drone's path relative to it against its
    disc."""
    def make() -> tuple[Visit, ...]:
        path = flight_path(ctx, drone_id)
        radius = ctx.vehicle(drone_id).task_radius_m
        shape = footprint(ctx, target_id)
        rows = target_rows(ctx, target_id)
        if rows is not None:
            path = path.relative_to(rows)
            shape = Footprint((0.0, 0.0), shape.bound_radius_m, shape.disc_radius_m, None, None)
        mask = path.in_range(shape, radius)
        return tuple(Visit(float(path.t0[f]), float(path.t1[e]))
                     for f, e in path.chains(mask))
    return ctx.cached(("visits", drone_id, target_id), make)
