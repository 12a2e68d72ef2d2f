"""A running swarm's faults: its link gate, and the timed events they bring in simulated time.

The transport asks the `LinkGate` each frame's fate (emulator.link_faults). What happens at a
simulated time is scheduled here and fired at exactly that physics step (the swarm never steps
past the next one): an outage window opening or closing (truth events `link_outage`,
`link_restored`), PX4's data-link-loss failsafe `COM_DL_LOSS_T` after the vehicle stopped
hearing any ground station (`link_lost`, then NAV_DLL_ACT; see emulator.flight.failures), and
vehicle failures a session schedules.

"Hears nothing" is decided by the fault model, not by heartbeat timing: the uplink is down
during an outage window, at 100 % loss, or while the vehicle's MAVLink is off. Ground-station
heartbeats come at wall-clock rates, and a stepped clock runs minutes of simulated time per
wall second, so timing them would make results depend on the machine.
"""

from __future__ import annotations

import heapq
import itertools
import math
from collections.abc import Callable
from typing import TYPE_CHECKING

from emulator.link_faults import DIRECTIONS, UPLINK, LinkFaults, LinkGate
from emulator.truth_events import TruthEventKind

if TYPE_CHECKING:
    from emulator.flight.autopilot import Autopilot
    from emulator.flight.fleet import Fleet

__all__ = ["SwarmFaults"]

_EPS = 1e-9


class SwarmFaults:
    """Link faults and scheduled failures of one swarm."""

    def __init__(self, fleet: Fleet, faults: LinkFaults | None = None) -> None:
        self._fleet = fleet
        ids = [ap.vehicle_id for ap in fleet.autopilots]
        self.gate = LinkGate(faults or LinkFaults(), ids,
                             lambda: (fleet.now_s, fleet.step_count))
        for ap in fleet.autopilots:
            ap.failures.silenced = self.gate.silenced
        self._events: list[tuple[float, int, str, Callable[[], None]]] = []
        self._order = itertools.count()
        self._link_events: set[int] = set()  # ids of scheduled events that belong to the links
        self.configure(faults or LinkFaults(), record=faults is not None)

    def add_vehicle(self, ap: Autopilot) -> None:
        """A vehicle joined the running swarm: its links follow the current settings."""
        self.gate.add_vehicle(ap.vehicle_id)
        ap.failures.silenced = self.gate.silenced

    # ------------------------------------------------------------ settings
    def configure(self, faults: LinkFaults, *, record: bool = True) -> None:
        """Use `faults` from now on (at start, or an operator's change at run time)."""
        fleet = self._fleet
        self.gate.configure(faults)
        self._events = [e for e in self._events if e[1] not in self._link_events]
        heapq.heapify(self._events)
        self._link_events.clear()
        now = fleet.now_s
        for ap in fleet.autopilots:
            k = ap.k
            if record:
                up, down = self.gate.profile(k, UPLINK), self.gate.profile(k, 1 - UPLINK)
                ap.event(TruthEventKind.LINK_FAULTS, seed=faults.seed, uplink=up.to_json(),
                         downlink=down.to_json())
            for name, direction in DIRECTIONS.items():
                for start, end in self.gate.profile(k, direction).outages:
                    if end <= now + _EPS:
                        continue
                    begin = max(start, now)
                    self._link_event(begin, "outage", self._outage_start(ap, name, begin, end))
                    self._link_event(end, "restored", self._outage_end(ap, name))
            if self.gate.link_down(k, now):
                self._schedule_link_check(ap)
            elif ap.failures.link_lost:
                ap.failures.data_link_regained()

    def _link_event(self, t_s: float, kind: str, action: Callable[[], None]) -> None:
        order = next(self._order)
        self._link_events.add(order)
        heapq.heappush(self._events, (t_s, order, kind, action))

    def schedule(self, t_s: float, kind: str, action: Callable[[], None]) -> None:
        """Run `action` at simulated time t_s (a vehicle failure a session schedules)."""
        heapq.heappush(self._events, (max(t_s, self._fleet.now_s), next(self._order), kind,
                                      action))

    def clear_scheduled(self) -> None:
        """Drop every scheduled event that is not the links' own (a task's failures)."""
        self._events = [e for e in self._events if e[1] in self._link_events]
        heapq.heapify(self._events)

    def _outage_start(self, ap: Autopilot, direction: str, start_s: float, end_s: float
                      ) -> Callable[[], None]:
        def fire() -> None:
            ap.event(TruthEventKind.LINK_OUTAGE, direction=direction, until_s=end_s)
            if direction == "uplink":
                self._schedule_link_check(ap)
        return fire

    def _outage_end(self, ap: Autopilot, direction: str) -> Callable[[], None]:
        def fire() -> None:
            ap.event(TruthEventKind.LINK_RESTORED, direction=direction)
            if not self.gate.link_down(ap.k, self._fleet.now_s):
                ap.failures.data_link_regained()
        return fire

    def _schedule_link_check(self, ap: Autopilot) -> None:
        timeout_s = float(ap.params["COM_DL_LOSS_T"])
        since = self._fleet.now_s

        def check() -> None:
            # down now, and all along since `since` (no restore event came in between)
            if self.gate.link_down(ap.k, self._fleet.now_s) and self._down_since(ap.k, since):
                ap.failures.data_link_lost(timeout_s)
        self._link_event(since + timeout_s, "link_check", check)

    def _down_since(self, k: int, since_s: float) -> bool:
        if k in self.gate.silenced or self.gate.profile(k, UPLINK).loss >= 1.0:
            return True
        return any(start <= since_s + _EPS and self._fleet.now_s < end
                   for start, end in self.gate.profile(k, UPLINK).outages)

    def mavlink_signal_changed(self, ap: Autopilot) -> None:
        """A vehicle's MAVLink went off (failure injection) or came back."""
        if ap.failures.mavlink_off:
            self._schedule_link_check(ap)
        elif not self.gate.link_down(ap.k, self._fleet.now_s):
            ap.failures.data_link_regained()

    # ------------------------------------------------------------ stepping
    def next_event_s(self) -> float:
        return self._events[0][0] if self._events else math.inf

    def fire_due(self) -> bool:
        """Fire every event due at the present simulated time; True if any fired."""
        now = self._fleet.now_s
        fired = False
        while self._events and self._events[0][0] <= now + _EPS:
            _t, order, _kind, action = heapq.heappop(self._events)
            self._link_events.discard(order)
            action()
            fired = True
        return fired
