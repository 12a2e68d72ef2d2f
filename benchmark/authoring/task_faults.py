"""Faults a task schedules in its hidden part: failures and link degradation the agent is not
told about, at simulated times counted from the task's start.

A task object of a session file may carry ``faults`` (hidden, like ``checks`` and ``oracle``):

    "faults": {"failures": [{"drone": "d2", "after_s": 40, "unit": "motor"}],
               "link": {"loss": 0.2, "vehicles": {"d3": {"uplink": {"outages": [[10, 60]]}}}}}

``failures``: `unit` one of gps, motor, battery, mavlink (emulator.flight.failures), injected
`after_s` simulated seconds after the task starts. ``link``: link faults (emulator.link_faults)
for the task's duration, outage windows counted from the task's start; the session's own link
faults come back when the task ends. Both are recorded in the ground truth as they happen.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

from emulator.flight.failures import FAILURE_KINDS
from emulator.link_faults import LinkFaultError, LinkFaults, LinkProfile
from emulator.swarm import Swarm

__all__ = ["ScheduledFailure", "TaskFaults", "task_faults"]


@dataclass(frozen=True)
class ScheduledFailure:
    drone: str
    after_s: float
    unit: str


@dataclass(frozen=True)
class TaskFaults:
    failures: tuple[ScheduledFailure, ...]
    link: LinkFaults | None

    def apply(self, swarm: Swarm, t0_s: float) -> None:
        """Schedule the failures and put the task's link faults in force (at t0_s)."""
        fleet = swarm.fleet
        for failure in self.failures:
            ap = fleet.autopilots[fleet.index_by_id[failure.drone]]

            def fire(ap: Any = ap, unit: str = failure.unit) -> None:
                ap.failures.fail(unit, "schedule")
                if unit == "mavlink":
                    swarm.faults.mavlink_signal_changed(ap)
            swarm.faults.schedule(t0_s + failure.after_s, "failure", fire)
        if self.link is not None:
            swarm.set_link_faults(_shifted(self.link, t0_s))

    def end(self, swarm: Swarm, session_link: LinkFaults | None) -> None:
        """The task is over: drop failures still pending, restore the session's link."""
        swarm.faults.clear_scheduled()
        if self.link is not None:
            swarm.set_link_faults(session_link or LinkFaults())


def _shifted(faults: LinkFaults, t0_s: float) -> LinkFaults:
    def shift(p: LinkProfile) -> LinkProfile:
        return replace(p, outages=tuple((a + t0_s, b + t0_s) for a, b in p.outages))
    return replace(faults, uplink=shift(faults.uplink), downlink=shift(faults.downlink),
                   vehicles={v: (shift(u), shift(d)) for v, (u, d) in faults.vehicles.items()})


def task_faults(raw_task: Any, vehicle_ids: Sequence[str], where: str = "task"
                ) -> TaskFaults | None:
    """The task's ``faults``, or None; raises ValueError naming the field."""
    if not isinstance(raw_task, Mapping) or raw_task.get("faults") is None:
        return None
    raw = raw_task["faults"]
    where = f"{where}.faults"
    if not isinstance(raw, Mapping) or set(raw) - {"failures", "link"}:
        raise ValueError(f"{where}: expected an object with 'failures' and/or 'link'")
    failures = []
    listed = raw.get("failures", [])
    if not isinstance(listed, list):
        raise ValueError(f"{where}.failures: expected a list")
    for i, item in enumerate(listed):
        at = f"{where}.failures[{i}]"
        if not isinstance(item, Mapping) or set(item) != {"drone", "after_s", "unit"}:
            raise ValueError(f"{at}: expected {{drone, after_s, unit}}")
        if item["drone"] not in vehicle_ids:
            raise ValueError(f"{at}.drone: unknown drone {item['drone']!r}")
        after = item["after_s"]
        if isinstance(after, bool) or not isinstance(after, int | float) \
                or not (math.isfinite(after) and after >= 0.0):
            raise ValueError(f"{at}.after_s: expected simulated seconds >= 0, got {after!r}")
        if item["unit"] not in FAILURE_KINDS:
            raise ValueError(f"{at}.unit: expected one of {', '.join(FAILURE_KINDS)}")
        failures.append(ScheduledFailure(item["drone"], float(after), item["unit"]))
    link = None
    if "link" in raw:
        try:
            link = LinkFaults.from_json(raw["link"], f"{where}.link", list(vehicle_ids))
        except LinkFaultError as error:
            raise ValueError(str(error)) from None
    return TaskFaults(tuple(failures), link)
