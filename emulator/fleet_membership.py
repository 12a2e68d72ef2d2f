"""Vehicles joining and leaving a running swarm, between physics steps.

A fleet is sized for its vehicles at start (emulator.flight.fleet: one row per vehicle in every
array). `join` grows each of those arrays by one row for a new vehicle, which takes the next
index, so the next free MAVLink system id (index + 1): ids of vehicles that left are never
given again within the run. It speaks at once (heartbeat and telemetry on the swarm's shared
socket, so a MAVLink client discovers it), perceives and is perceived, flies under the
collision guard and is recorded in the ground truth from its join time on.

`leave` keeps the vehicle's row (indices never shift) but silences it: its streams stop, its
link leaves the network (commands to it go unanswered), it is frozen where it is, no longer
stepped, sensed or recorded; its truth history ends at its leave time. Both are recorded as
truth events (`joined`, `left`). A run without joins or leaves is untouched by this module.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import TYPE_CHECKING

import numpy as np

from emulator.flight import dynamics as dy
from emulator.flight.autopilot import Autopilot
from emulator.flight.battery import FleetBattery
from emulator.flight.dynamics import FleetDynamics
from emulator.flight.listener import SilentListener
from emulator.mavlink.vehicle_link import VehicleLink
from emulator.networks import VEHICLES_PER_NETWORK
from emulator.scenario import VehicleSpec
from emulator.truth_events import TruthEventKind

if TYPE_CHECKING:
    from emulator.flight.fleet import Fleet
    from emulator.swarm import Swarm

__all__ = ["MAX_VEHICLES", "join", "leave", "present_ids"]

MAX_VEHICLES = VEHICLES_PER_NETWORK
"""A joinable swarm's limit (one MAVLink network), counting vehicles that left: MAVLink system
ids are never reused within a run."""

_DYN_ROWS = ("position_m", "velocity_m_s", "accel_m_s2", "yaw_deg", "control", "goal_m",
             "goal_yaw_deg", "velocity_sp_m_s", "tracking", "yaw_tracking", "_lim_h", "_lim_v",
             "_along_h", "_along_v", "airspeed_max_m_s", "climb_m_s", "descent_m_s",
             "yaw_rate_deg_s", "acceptance_m")
_BATTERY_ROWS = ("pct", "hover_endurance_s", "charge_rate_pct_s", "level")
_DYN_VIEWS = (("speed_xy_m_s", "_lim_h", 0), ("accel_xy_m_s2", "_lim_h", 1),
              ("accel_z_m_s2", "_lim_v", 1))
_FLEET_ROWS = ("armed", "airborne", "busy", "ended", "stop_on", "timer_s")


def _grow_rows(obj: object, fresh: object, names: tuple[str, ...]) -> None:
    """Append `fresh`'s one-vehicle row to each per-vehicle array `names` of `obj`."""
    for name in names:
        setattr(obj, name, np.concatenate([getattr(obj, name), getattr(fresh, name)]))


def _grow_dynamics(dyn: FleetDynamics) -> None:
    n = dyn.n
    _grow_rows(dyn, FleetDynamics(1), _DYN_ROWS)
    for view, base, col in _DYN_VIEWS:
        setattr(dyn, view, getattr(dyn, base)[:, col])
    if dyn.yaw_step_deg is not None:
        dyn.yaw_step_deg = np.append(dyn.yaw_step_deg, 0.0)
    dyn.n = n + 1


def _grow_battery(bat: FleetBattery) -> None:
    fresh = FleetBattery(1)
    _grow_rows(bat, fresh, _BATTERY_ROWS)
    bat.levels_pct = np.concatenate([bat.levels_pct, fresh.levels_pct], axis=1)
    bat.low_pct, bat.critical_pct, bat.emergency_pct = bat.levels_pct[:3]


def _grow_fleet(fleet: Fleet, spec: VehicleSpec, shared_origin: bool) -> int:
    """Room for one more vehicle in every array of `fleet`; returns its index."""
    n = fleet.n
    _grow_dynamics(fleet.dyn)
    _grow_battery(fleet.bat)
    for name in _FLEET_ROWS:
        old = getattr(fleet, name)
        setattr(fleet, name, np.append(old, math.inf if name == "timer_s" else False))
    origin = (0.0, 0.0, 0.0) if shared_origin else (spec.position_m[0], spec.position_m[1], 0.0)
    fleet.local_origin_m = np.vstack([fleet.local_origin_m, origin])
    fleet.guard.check_at_s = np.append(fleet.guard.check_at_s, 0.0)
    fleet.guard.forget(n)
    return n


def _check_spec(swarm: Swarm, spec: VehicleSpec) -> None:
    fleet = swarm.fleet
    if swarm.ports.per_vehicle:
        raise ValueError("vehicles join a swarm on one shared socket only, not with "
                         "per-vehicle ports")
    if spec.id in fleet.recorder.vehicle_ids:
        raise ValueError(f"drone id {spec.id!r} is taken in this run (ids of drones that "
                         "left are not reused)")
    if fleet.n >= MAX_VEHICLES:
        raise ValueError(f"a swarm holds at most {MAX_VEHICLES} vehicles over a run "
                         "(MAVLink system ids are not reused)")


def join(swarm: Swarm, spec: VehicleSpec) -> int:
    """Add vehicle `spec` to the running `swarm` now; returns its index (system id - 1).
    ValueError (nothing changed) for a taken id, a full swarm or per-vehicle ports."""
    _check_spec(swarm, spec)
    fleet = swarm.fleet
    k = _grow_fleet(fleet, spec, swarm.shared_local_origin)
    fleet.index_by_id[spec.id] = k
    fleet.scenario = dataclasses.replace(fleet.scenario,
                                         vehicles=(*fleet.scenario.vehicles, spec))
    ap = Autopilot(k, spec, fleet)
    fleet.autopilots.append(ap)
    if swarm.clock.stepped:
        ap.set_param("COM_DISARM_PRFLT", -1.0)
    dyn = fleet.dyn
    fleet.recorder.add_vehicle(spec.id, fleet.now_s, dyn.position_m[k], float(dyn.yaw_deg[k]),
                               float(fleet.bat.pct[k]))
    swarm.faults.add_vehicle(ap)
    wall = time.monotonic()
    swarm.streams.add_vehicle(wall)
    telemetry = swarm.telemetry
    telemetry.system_ids = np.append(telemetry.system_ids, np.uint8(ap.system_id))
    network = swarm.networks[0]
    link = VehicleLink(ap, network.send_frame, swarm.streams, time.monotonic)
    swarm.links.append(link)
    swarm.network_of.append(network)
    for component, sequences in list(telemetry.sequences.items()):
        grown = np.append(sequences, np.uint8(0))
        for other in swarm.links:  # every encoder counts in the grown array from now on
            other.encoder(component).share_sequence(grown, other.k)
        grown[:k] = sequences
        telemetry.sequences[component] = grown
    swarm.hook_link(link)
    network.add(link)
    swarm.watches.add_vehicle()
    ap.event(TruthEventKind.JOINED, system_id=ap.system_id,
             position_m=[float(v) for v in dyn.position_m[k]])
    swarm.send_telemetry_of(spec.id)
    return k


def leave(swarm: Swarm, drone_id: str) -> None:
    """Take `drone_id` out of the running `swarm` now: it stops speaking and moving, and its
    history ends here. KeyError for a drone not in the swarm (never there, or left)."""
    fleet = swarm.fleet
    k = fleet.index_by_id.get(drone_id)
    if k is None:
        raise KeyError(f"drone {drone_id!r} is not in the swarm")
    ap = fleet.autopilots[k]
    dyn = fleet.dyn
    ap.event(TruthEventKind.LEFT, system_id=ap.system_id,
             position_m=[float(v) for v in dyn.position_m[k]])
    ap.listener = SilentListener()
    ap.mission.pause()
    ap.cancel_timer()
    ap.drop_goal()
    dyn.velocity_m_s[k] = 0.0
    dyn.accel_m_s2[k] = 0.0
    dyn.velocity_sp_m_s[k] = 0.0
    dyn.control[k] = dy.CONTROL_NONE
    dyn.tracking[k] = dy.TRACK_NONE
    dyn.yaw_tracking[k] = False
    fleet.armed[k] = fleet.airborne[k] = fleet.busy[k] = False
    fleet.ended[k] = True  # a watch on it halts
    fleet.timer_s[k] = math.inf
    fleet.bat.charge_rate_pct_s[k] = 0.0
    del fleet.index_by_id[drone_id]
    fleet.recorder.retire(drone_id)
    swarm.streams.period_s[k] = math.inf
    swarm.streams.next_due_s[k] = math.inf
    link = swarm.links[k]
    swarm.network_of[k].links.pop(link.system_id, None)
    swarm.left.add(k)
    if swarm.clock.stepped:  # a client waiting on it goes on now (the clock may be at rest)
        swarm.watches.check()
    swarm.wake()


def present_ids(fleet: Fleet) -> list[str]:
    """The ids of the vehicles in the swarm now, in system-id order."""
    return sorted(fleet.index_by_id, key=fleet.index_by_id.__getitem__)

