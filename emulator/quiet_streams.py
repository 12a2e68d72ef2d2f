"""Quiet streams: on a lockstep clock, a periodic stream carries a vehicle's message only when
it may show something its client has not yet been sent.

While a lockstep clock stands still (every agent thinking) nothing a stream reports can change,
so sending the same values again at every period only costs both ends CPU; PX4 in lockstep
SITL sends nothing at all while its simulator pauses. Here the keep-alive streams (the
autopilot's and the camera's heartbeats) keep their rates, so a client keeps its links, and
every other stream of a vehicle goes out at its next period once the vehicle may have changed
(the same signals as a halt's burst: armed, airborne, busy or charging at a step, a message
that is not a query, an autopilot event, a fault) and not again until it changes once more.
Every stream goes out at its rate for NEW_PEER_FULL_S after a new ground station talks to the
network (its subscriptions start after it has heard of the vehicles), and everything is sent
again every REFRESH_S of wall time, so a client that starts late, or lost a datagram, catches
up.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator

import numpy as np

from emulator.mavlink.streams import CAMERA_HEARTBEAT, StreamSpec
from mavlink_vocabulary import MessageId

__all__ = ["KEEP_ALIVE_STREAMS", "NEW_PEER_FULL_S", "REFRESH_S", "QuietStreams"]

KEEP_ALIVE_STREAMS = frozenset({int(MessageId.HEARTBEAT), CAMERA_HEARTBEAT})
REFRESH_S = 20.0
NEW_PEER_FULL_S = 5.0


class QuietStreams:
    """Which (vehicle, stream) pairs may show something not yet sent (`stale`)."""

    def __init__(self, n: int, streams: tuple[StreamSpec, ...], wall_now_s: float) -> None:
        self.column = {s.msg_id: i for i, s in enumerate(streams)}
        self.stale = np.ones((n, len(streams)), dtype=bool)
        self._next_refresh_s = wall_now_s + REFRESH_S
        self._full_until_s = wall_now_s + NEW_PEER_FULL_S

    def _grow(self, n: int) -> None:
        if n > len(self.stale):  # vehicles that joined: nothing of theirs sent yet
            extra = np.ones((n - len(self.stale), self.stale.shape[1]), dtype=bool)
            self.stale = np.vstack([self.stale, extra])

    # ------------------------------------------------------------ what changed
    def mark(self, ks: Iterable[int]) -> None:
        """These vehicles may have changed: each of their streams goes out at its next due."""
        ks = list(ks)
        if ks:
            self._grow(max(ks) + 1)
            self.stale[ks] = True

    def mark_all(self) -> None:
        self.stale[:] = True

    def new_peer(self, wall_now_s: float) -> None:
        """A ground station began talking: every stream at its rate for a while."""
        self._full_until_s = wall_now_s + NEW_PEER_FULL_S

    def sent(self, ks: np.ndarray) -> None:
        """Every stream of vehicles ks went out (a burst)."""
        if len(ks):
            self._grow(int(ks.max()) + 1)
            self.stale[ks] = False

    # ---------------------------------------------------------------- sending
    def filter(self, due: Iterable[tuple[int, np.ndarray]], wall_now_s: float
               ) -> Iterator[tuple[int, np.ndarray]]:
        """The due (msg_id, vehicles) pairs worth sending: keep-alives always, the others for
        the vehicles stale in that stream (which then count as sent)."""
        if wall_now_s >= self._next_refresh_s or wall_now_s < self._full_until_s:
            self._next_refresh_s = wall_now_s + REFRESH_S
            self.mark_all()
        for msg_id, ks in due:
            if msg_id in KEEP_ALIVE_STREAMS or not len(ks):
                yield msg_id, ks
                continue
            self._grow(int(ks.max()) + 1)
            col = self.column[msg_id]
            keep = ks[self.stale[ks, col]]
            if len(keep):
                self.stale[keep, col] = False
                yield msg_id, keep
