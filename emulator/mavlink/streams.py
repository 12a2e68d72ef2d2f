"""Periodic telemetry streams, scheduled on the wall clock for every vehicle at once.

Rates are wall-clock rates whatever the simulation speed, so a ground station is neither
flooded at a high speed-up nor starved when simulated time stands still. Phases are
staggered by vehicle so a large swarm does not send in bursts.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass

import numpy as np

from mavlink_vocabulary import MessageId

__all__ = ["CAMERA_HEARTBEAT", "DEFAULT_STREAMS", "StreamSchedule", "StreamSpec"]

CAMERA_HEARTBEAT = -1  # pseudo message id: the camera component's heartbeat


@dataclass(frozen=True, slots=True)
class StreamSpec:
    msg_id: int
    name: str
    default_hz: float


DEFAULT_STREAMS: tuple[StreamSpec, ...] = tuple(
    StreamSpec(msg_id, name, hz) for msg_id, name, hz in (
        (MessageId.HEARTBEAT, "HEARTBEAT", 1.0),
        (MessageId.SYS_STATUS, "SYS_STATUS", 1.0),
        (MessageId.EXTENDED_SYS_STATE, "EXTENDED_SYS_STATE", 1.0),
        (MessageId.GLOBAL_POSITION_INT, "GLOBAL_POSITION_INT", 10.0),
        (MessageId.LOCAL_POSITION_NED, "LOCAL_POSITION_NED", 10.0),
        (MessageId.ATTITUDE, "ATTITUDE", 10.0),
        (MessageId.GPS_RAW_INT, "GPS_RAW_INT", 1.0),
        (MessageId.VFR_HUD, "VFR_HUD", 2.0),
        (MessageId.MISSION_CURRENT, "MISSION_CURRENT", 1.0),
        (MessageId.BATTERY_STATUS, "BATTERY_STATUS", 0.5),
        (MessageId.HOME_POSITION, "HOME_POSITION", 0.5),
        (CAMERA_HEARTBEAT, "CAMERA_HEARTBEAT", 1.0),
        (MessageId.HIGHRES_IMU, "HIGHRES_IMU", 0.0),  # off until a client sets its rate
    )
)


class StreamSchedule:
    """When each (vehicle, stream) pair is next due, in wall-clock seconds."""

    def __init__(self, n: int, wall_now_s: float, rates_hz: Mapping[str, float] | None = None,
                 streams: tuple[StreamSpec, ...] = DEFAULT_STREAMS) -> None:
        rates = dict(rates_hz or {})
        unknown = set(rates) - {s.name for s in streams}
        if unknown:
            raise ValueError(f"unknown telemetry streams {sorted(unknown)}")
        self.streams = streams
        self.column = {s.msg_id: i for i, s in enumerate(streams)}
        hz = np.array([rates.get(s.name, s.default_hz) for s in streams], dtype=float)
        if (hz < 0).any():
            raise ValueError("telemetry rates must be >= 0 Hz (0 disables a stream)")
        with np.errstate(divide="ignore"):
            period = np.where(hz > 0, 1.0 / hz, math.inf)
        self.default_period_s = period
        self.period_s = np.tile(period, (n, 1))
        stagger = (np.arange(n) / max(n, 1))[:, None]
        finite = np.isfinite(period)
        self.next_due_s = wall_now_s + np.where(finite, np.where(finite, period, 0.0) * stagger,
                                                math.inf)

    def add_vehicle(self, wall_now_s: float) -> None:
        """One more vehicle (joining a running swarm) with the default rates, due now."""
        period = self.default_period_s
        self.period_s = np.vstack([self.period_s, period])
        due = np.where(np.isfinite(period), wall_now_s, math.inf)
        self.next_due_s = np.vstack([self.next_due_s, due])

    def due(self, wall_now_s: float) -> Iterator[tuple[int, np.ndarray]]:
        """(msg_id, vehicle indices) for every stream with something due; reschedules them."""
        ks, cols = np.nonzero(self.next_due_s <= wall_now_s)  # by vehicle, then stream
        if not len(ks):
            return
        period = self.period_s[ks, cols]
        nxt = self.next_due_s[ks, cols] + period
        late = nxt <= wall_now_s
        nxt[late] = wall_now_s + period[late]
        self.next_due_s[ks, cols] = nxt
        by_stream = np.argsort(cols, kind="stable")  # each stream's vehicles in index order
        ks, cols = ks[by_stream], cols[by_stream]
        starts = np.flatnonzero(np.diff(cols, prepend=-1)).tolist()
        for first, last in zip(starts, [*starts[1:], len(ks)], strict=True):
            yield self.streams[int(cols[first])].msg_id, ks[first:last]

    def set_interval(self, k: int, msg_id: int, interval_s: float | None,
                     wall_now_s: float) -> bool:
        """Change one vehicle's stream period (None: default, inf: off). False if unknown."""
        col = self.column.get(msg_id)
        if col is None:
            return False
        period = self.default_period_s[col] if interval_s is None else interval_s
        self.period_s[k, col] = period
        self.next_due_s[k, col] = wall_now_s + period if math.isfinite(period) else math.inf
        return True

    def interval_s(self, k: int, msg_id: int) -> float | None:
        col = self.column.get(msg_id)
        return None if col is None else float(self.period_s[k, col])

    def enabled(self, k: int) -> list[int]:
        """The message ids of vehicle k's streams that are on."""
        return [self.streams[c].msg_id for c in np.flatnonzero(np.isfinite(self.period_s[k]))]

    def shortest_period_s(self) -> float:
        """The shortest period of any stream of any vehicle (inf when all are off)."""
        return float(self.period_s.min()) if self.period_s.size else math.inf

    def next_wakeup_s(self) -> float:
        return float(self.next_due_s.min())
