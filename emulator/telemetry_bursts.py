"""Bursts: a vehicle's whole telemetry at once, outside its streams' periods.

A lockstep halt sends the halted vehicle's telemetry twice (a client waits for two agreeing
messages) and every other vehicle's once, so a client's caches show the stopped clock's state
whatever the stream rates; an operator's reset sends everyone's; a client may ask for one
vehicle's. At a halt, only the other vehicles whose telemetry may differ from what they last
sent in a burst go out: those armed, airborne, executing a goal or charging at any step since,
those a message or an autopilot event may have changed (anything but a query, see
emulator.mavlink.queries), all of them after a fault fired, and those with a failure to report
again. A vehicle at rest on the ground otherwise shows the same values at every halt, and a
large swarm's client would read the same telemetry again for each of them after every goal of
every other drone.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from emulator.flight.fleet import Fleet
    from emulator.quiet_streams import QuietStreams

__all__ = ["BURST_VEHICLES_PER_TURN", "TelemetryBursts"]

# Vehicles whose whole telemetry goes out in one loop turn; the others follow on the next
# turns. A ground station's MAVSDK hands every message to its subscribers through one bounded
# queue and drops callbacks once a burst overflows it (every vehicle of a large swarm at once
# does), so the client would wait for telemetry asked again.
BURST_VEHICLES_PER_TURN = 3


class TelemetryBursts:
    """The bursts still to send (vehicle -> times) and the vehicles changed since theirs."""

    def __init__(self, fleet: Fleet, quiet: QuietStreams | None = None) -> None:
        """quiet: the swarm's quiet streams (a lockstep clock), told of every change too."""
        self._fleet = fleet
        self.quiet = quiet
        self.pending: dict[int, int] = {}
        self._changed: set[int] = set(range(fleet.n))

    # ------------------------------------------------------------ what changed
    def changed(self, k: int) -> None:
        """Vehicle k's state may have changed (a message, an autopilot event)."""
        self._changed.add(k)
        if self.quiet is not None:
            self.quiet.mark((k,))

    def all_changed(self) -> None:
        """Every vehicle's state may have changed (a fault fired)."""
        self._changed.update(range(self._fleet.n))
        if self.quiet is not None:
            self.quiet.mark_all()

    def note_active(self) -> None:
        """Before physics steps: the vehicles they may change (at rest, one stays as it is)."""
        f = self._fleet
        active = f.armed | f.airborne | f.busy | (f.bat.charge_rate_pct_s > 0.0)
        if active.any():
            ks = np.flatnonzero(active).tolist()
            self._changed.update(ks)
            if self.quiet is not None:
                self.quiet.mark(ks)

    # --------------------------------------------------------------- requests
    def first(self, k: int, count: int) -> None:
        """Vehicle k's burst, `count` times, before every other one pending."""
        pending = self.pending
        self.pending = {k: max(count, pending.pop(k, 0))}
        self.pending.update(pending)

    def everyone(self) -> None:
        """Every vehicle's burst (an operator's reset)."""
        for k in range(self._fleet.n):
            self.pending.setdefault(k, 1)

    def halt(self, k: int, *, also: set[int] | None = None, every_vehicle: bool = False
             ) -> None:
        """A lockstep halt of vehicle k: its burst twice, then once each other vehicle's that
        changed since its last burst (and those in `also`; `every_vehicle`: all of them)."""
        self.first(k, 2)
        others = range(self._fleet.n) if every_vehicle else sorted(self._changed | (also or set()))
        for other in others:
            self.pending.setdefault(other, 1)

    # ---------------------------------------------------------------- sending
    def take_turn(self, left: set[int]) -> dict[int, int]:
        """The bursts to send on this loop turn (at most BURST_VEHICLES_PER_TURN vehicles,
        none that left the run); they count as sent."""
        pending = self.pending
        if len(pending) <= BURST_VEHICLES_PER_TURN:
            turn, self.pending = pending, {}
        else:
            turn = {k: pending.pop(k) for k in list(pending)[:BURST_VEHICLES_PER_TURN]}
        for k in left:
            turn.pop(k, None)
        self._changed.difference_update(turn)
        again = {k: count - 1 for k, count in turn.items() if count > 1}
        if again:  # on the next turn, before the vehicles still waiting for their first
            again.update(self.pending)
            self.pending = again
        return turn
