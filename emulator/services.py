"""What a swarm offers its gateway besides MAVLink: the clock, each drone's sensor feed, the
drone-to-drone radio, and operator controls.

Flight goes through MAVLink only. These services carry what MAVLink has no message for
(what a drone's sensor perceives, text between drones) and the operator's resets between
benchmark tasks, which are marked `operator_*` and recorded as such in the ground truth.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator, Mapping
from typing import Any

from emulator.flight.battery import MESSAGE_COST_PCT
from emulator.flight.operator import place_on_ground, set_battery
from emulator.link_faults import DOWNLINK, UPLINK, LinkFaultError, LinkFaults
from emulator.lockstep import Watch
from emulator.perception import Perception
from emulator.radio import Message, Radio
from emulator.swarm import Swarm

__all__ = ["MAX_OUTAGE_WINDOWS", "SwarmServices"]

MAX_OUTAGE_WINDOWS = 64
"""Outage windows an operator may set per direction of a link (each schedules events)."""


def _check_windows(faults: LinkFaults) -> None:
    pairs = [("", faults.uplink, faults.downlink)] + [
        (f"vehicles.{vid}.", up, down) for vid, (up, down) in faults.vehicles.items()]
    for where, up, down in pairs:
        for name, profile in (("uplink", up), ("downlink", down)):
            if len(profile.outages) > MAX_OUTAGE_WINDOWS:
                raise LinkFaultError(f"link_faults.{where}{name}.outages: "
                                     f"{len(profile.outages)} windows; at most "
                                     f"{MAX_OUTAGE_WINDOWS} per direction")


class SwarmServices:
    """In-process services of one running swarm."""

    def __init__(self, swarm: Swarm) -> None:
        self._swarm = swarm
        self._fleet = swarm.fleet
        ids = [ap.vehicle_id for ap in self._fleet.autopilots]
        self.radio = Radio(ids, self._fleet.recorder, self.clock_s)

    @property
    def drone_ids(self) -> tuple[str, ...]:
        """The drones in the swarm now (those that left are gone), in system-id order."""
        index = self._fleet.index_by_id
        return tuple(ap.vehicle_id for ap in self._fleet.autopilots if ap.vehicle_id in index)

    def add_drone(self, drone_id: str) -> None:
        """A drone joined the swarm (emulator.fleet_membership.join): it has a radio."""
        self.radio.add_drone(drone_id)

    def remove_drone(self, drone_id: str) -> None:
        """A drone left the swarm: messages to it are refused from now on."""
        self.radio.remove_drone(drone_id)

    def clock_s(self) -> float:
        """Simulated time now."""
        return self._fleet.now_s

    # -------------------------------------------------------------- lockstep
    @property
    def lockstep(self) -> bool:
        """Simulated time runs only while every client waits on the world."""
        return self._swarm.clock.lockstep

    def pin(self) -> object:
        """Stop the clock here (a client is thinking) until `unpin(token)`."""
        return self._swarm.pin()

    def unpin(self, token: object) -> None:
        self._swarm.release_clock(token)

    def refresh_telemetry(self, drone_id: str) -> None:
        """Send every telemetry stream of drone_id at once (the clock is stopped and the
        client wants the state it stopped in, whatever the stream rates)."""
        self._swarm.send_telemetry_of(drone_id)

    def repeat_status_texts(self, drone_id: str) -> int:
        """Send again the STATUSTEXTs drone_id sent at the present simulated time (the clock
        is stopped at a halt and the client saw nothing explain it: texts are not periodic,
        and one lost on the way, or dropped by the client under load, is otherwise gone).
        Returns how many were sent again."""
        return self._swarm.repeat_status_texts(drone_id)

    def watch(self, drone_id: str | None = None, *, until_s: float = math.inf,
              advance: bool = False, message_for: str | None = None) -> Watch:
        """Wait on the world (see emulator.lockstep.Watch)."""
        return self._swarm.watch(drone_id, until_s=until_s, advance=advance,
                                 message_for=message_for)

    def _autopilot(self, drone_id: str):
        index = self._fleet.index_by_id.get(drone_id)
        if index is None:
            raise KeyError(f"unknown drone {drone_id!r}")
        return self._fleet.autopilots[index]

    def sense(self, drone_id: str) -> Perception:
        """What drone_id's sensor perceives now (its SIM_SENS_RAD disc)."""
        ap = self._autopilot(drone_id)
        present = self._fleet.index_by_id
        others = {o.vehicle_id: o.position_m for o in self._fleet.autopilots
                  if o is not ap and o.vehicle_id in present}
        return self._fleet.sensor.sense(ap.position_m, ap.params["SIM_SENS_RAD"],
                                        vehicles=others, exclude_vehicle=drone_id)

    # ------------------------------------------------------------------ radio
    def send_message(self, sender: str, recipient: str, text: str) -> Message:
        message = self.radio.send(sender, recipient, text)
        self._fleet.bat.spend(self._fleet.index_by_id[sender], MESSAGE_COST_PCT)
        self._announce([recipient])
        return message

    def broadcast(self, sender: str, text: str) -> int:
        count = self.radio.broadcast(sender, text)
        self._fleet.bat.spend(self._fleet.index_by_id[sender], MESSAGE_COST_PCT)
        self._announce([d for d in self.drone_ids if d != sender])
        return count

    def _announce(self, recipients: list[str]) -> None:
        if self.lockstep:  # readable one physics step after it was sent
            ready_s = self._fleet.now_s + self._fleet.dt_s
            for recipient in recipients:
                self._swarm.watches.message_ready(recipient, ready_s)

    def read_messages(self, drone_id: str) -> list[Message]:
        if self.lockstep:
            return self.radio.read(drone_id, sent_before_s=self._fleet.now_s - 1e-9)
        return self.radio.read(drone_id)

    # --------------------------------------------------------------- operator
    def operator_land_all(self) -> None:
        """Operator reset: every drone disarmed on the ground below where it is."""
        for ap in self._fleet.autopilots:
            x, y, _ = ap.position_m
            place_on_ground(ap, x, y)
        self._swarm.send_all_telemetry()

    def operator_reset_batteries(self, pct: float = 100.0) -> None:
        """Operator reset: every battery set to pct."""
        for ap in self._fleet.autopilots:
            set_battery(ap, pct)
        self._swarm.send_all_telemetry()

    def operator_reset_to_start(self) -> None:
        """Operator reset: every drone back at its scenario start, on the ground, full."""
        for ap in self._fleet.autopilots:
            x, y, _ = ap.spec.position_m
            place_on_ground(ap, x, y, ap.spec.heading_deg)
            ap.home_m = ap.spec.home_m
            ap.listener.on_home_changed()  # HOME_POSITION now, not at its next 0.5 Hz slot
            set_battery(ap, ap.spec.battery_pct)
        self.radio.clear()
        self._swarm.send_all_telemetry()

    def operator_link_faults(self) -> dict[str, Any]:
        """The link faults in force (`LinkFaults.to_json()`: seed, the swarm-wide uplink and
        downlink, and the vehicles with settings of their own)."""
        return self._swarm.faults.gate.faults.to_json()

    def operator_set_link_faults(self, settings: object) -> dict[str, Any]:
        """Operator: link faults from now on (a session file's ``link_faults`` object, which
        replaces every setting in force; see emulator.link_faults); recorded in the ground
        truth. Bad settings raise LinkFaultError (a ValueError) naming the field, and change
        nothing. Returns the settings now in force."""
        faults = LinkFaults.from_json(settings, "link_faults", list(self.drone_ids))
        _check_windows(faults)
        self._swarm.set_link_faults(faults)
        return faults.to_json()

    def operator_vehicle_link(self, drone_id: str) -> dict[str, Any]:
        """drone_id's link as it is in force: ``{"uplink": {...}, "downlink": {...}}``."""
        k = self._autopilot(drone_id).k
        gate = self._swarm.faults.gate
        return {"uplink": gate.profile(k, UPLINK).to_json(),
                "downlink": gate.profile(k, DOWNLINK).to_json()}

    def operator_set_vehicle_link(self, drone_id: str, settings: object) -> dict[str, Any]:
        """Operator: drone_id's own link settings from now on (a session file's
        ``link_faults.vehicles`` entry: profile fields for both directions, ``uplink`` /
        ``downlink`` objects for one, on top of the swarm-wide settings); the other vehicles
        keep theirs. Validated as `operator_set_link_faults`; returns the vehicle's link."""
        if drone_id not in self._fleet.index_by_id:
            raise LinkFaultError(f"unknown drone {drone_id[:40]!r} (drones: "
                                 f"{', '.join(self.drone_ids)})")
        if not isinstance(settings, Mapping):
            raise LinkFaultError(f"the link settings of {drone_id} must be an object of "
                                 "loss, latency_ms, jitter_ms, duplicate, reorder, outages, "
                                 "uplink, downlink")
        current = self._swarm.faults.gate.faults.to_json()
        vehicles = dict(current["vehicles"])
        vehicles[drone_id] = settings
        faults = LinkFaults.from_json({**current, "vehicles": vehicles}, "link",
                                      list(self.drone_ids))
        _check_windows(faults)
        self._swarm.set_link_faults(faults)
        return self.operator_vehicle_link(drone_id)

    def operator_clear_messages(self) -> None:
        """Operator reset: every drone's inbox emptied."""
        self.radio.clear()

    def operator_snapshot(self) -> dict[str, dict[str, list[float] | float]]:
        """Where every drone stands (ground truth): position, heading and home, for a later
        `operator_restore` of the same layout."""
        return {
            ap.vehicle_id: {"position_m": [float(v) for v in ap.position_m],
                            "heading_deg": float(self._fleet.dyn.yaw_deg[ap.k]),
                            "home_m": [float(v) for v in ap.home_m]}
            for ap in self._fleet.autopilots
        }

    def operator_restore(self, snapshot: Mapping[str, Mapping[str, Any]]) -> None:
        """Operator reset: drones put on the ground where a snapshot had them, with its homes."""
        for drone_id, spot in snapshot.items():
            ap = self._autopilot(drone_id)
            x, y, _ = spot["position_m"]
            place_on_ground(ap, float(x), float(y), float(spot["heading_deg"]))
            hx, hy, hz = (float(v) for v in spot["home_m"])
            ap.home_m = (hx, hy, hz)
            ap.listener.on_home_changed()
        self._swarm.send_all_telemetry()

    @contextlib.contextmanager
    def clock_limit(self, t_s: float) -> Iterator[None]:
        """While inside, a stepped clock does not run past simulated time t_s."""
        token = self._swarm.hold_clock_at(t_s)
        try:
            yield
        finally:
            self._swarm.release_clock(token)

    async def advance(self, seconds: float) -> None:
        """Let simulated time pass (stepped mode: run the clock; real time: wait)."""
        await self._swarm.advance(seconds)
