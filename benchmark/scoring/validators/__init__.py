"""Hidden validators: check trees evaluated on the emulator's ground truth of a task window.

A tree (see :mod:`benchmark.scoring.validators.tree`) is parsed with :func:`parse_tree` and
evaluated
with :func:`evaluate` on a :class:`CheckContext` (truth history, scenario, window [t0_s, t1_s]).
Endpoint and parameter names are the reference platform's; ``session_id`` and
``since_timestamp`` are accepted and ignored because every check sees only its own window.

Common semantics
    * Distances given x and y compare in 2D; given x, y and z, in 3D. Distances to a target or
      obstacle are 2D distances to its footprint (0 inside); disc-shaped targets (fixed,
      moving, waypoint, circle) are exact circles of their radius. Drone-to-drone distances
      are 3D.
    * Airborne means z >= 1.0 m. Speeds come from consecutive truth samples. Operator resets
      (``operator_place``, ``operator_battery``) are jumps, never flown path.
    * A drone's home at time t is the position of its last ``home`` event at or before t,
      else the scenario's home. Heading delta = |((a - b + 180) mod 360) - 180|.

State checks (kind "state") read the instant t1_s
    * Derived status: on the ground (z < 1 m) -> idle (matches idle, ready); airborne with a
      max speed over [t1 - 1 s, t1] below 0.5 m/s -> hovering; else moving (matches moving,
      flying, taking_off, landing).
    * drone_on_ground: z <= tolerance and current speed (last sample step) < 0.5 m/s;
      drone_hovering: z > tolerance and max speed over the last second < 0.5 m/s (value: that
      speed). all_drones_* are false for a scenario without drones.
    * drone_in_target: inside the footprint; the *_within_* checks compare the 2D footprint
      distance with max_distance, the task radius or the perceived radius.

Target checks (kind "targets") read the window
    * A drone reaches a target when a segment of its airborne polyline (joined consecutive
      samples at z >= 1 m) comes within its task radius (2D) of the footprint, so passing
      between two samples counts. A visit is a maximal run of connected in-range segments; a
      drone already in range at t0 counts one visit. moving_target_tracked uses the longest
      visit period.
    * Coverage of an area target (circle, polygon): area(footprint & union of every drone's
      airborne path, simplified by 0.5 m, buffered by its task radius) / area(footprint).
      Point-type targets: 1.0 when reached by some drone, else 0.0.
    * task_progress excludes waypoint targets (charging stations). area_search and
      area_assignment_and_patrol: floor(100 * mean coverage) / 100 (1.0 without targets);
      target_assignment: floor(100 * reached / count) / 100; other task types: reached /
      count (0 without targets). task_done: area families need every target covered >= 0.9;
      others need every target reached (false without targets).

History checks (kind "history") read events and trajectory in the window
    * drone_has_taken_off counts ``takeoff_complete`` events whose z lies in
      [min - tol, max + tol]; drone_has_landed counts ``landed`` events (a reference
      template's stray max_altitude parameter is accepted and ignored).
    * drone_has_visited_position: closest distance of the flown polyline (all joined segments,
      3D when z is given) to the point; drone_has_moved_distance: horizontal path length;
      drone_has_moved_directed_distance: horizontal length of segments >= 1 mm whose bearing
      atan2(dx, dy) is within tolerance of heading.
    * drone_has_hovered: maximal airborne periods at speed < 0.3 m/s lasting >= min_duration
      (1 s when absent). Photos, messages (sent to the recipient, plus broadcasts) and charges
      come from their events; a charge runs from ``charging`` to the next ``charged``, arm,
      takeoff or operator reset of the drone (or t1), and counts when it added
      >= min_charge_amount (> 0 when absent) or ended at >= 99.9 %.

Evaluation never raises for a leaf: a leaf that cannot run (unknown id, no truth samples)
gets result None, an error text and passed False.
"""

from __future__ import annotations

from benchmark.scoring.validators._errors import CheckDefinitionError, EvaluationError
from benchmark.scoring.validators.context import CheckContext
from benchmark.scoring.validators.endpoint import Endpoint, Outcome
from benchmark.scoring.validators.params import ParamSpec
from benchmark.scoring.validators.registry import ENDPOINTS
from benchmark.scoring.validators.tree import (
    Evaluation,
    Group,
    Leaf,
    LeafResult,
    Node,
    endpoints_used,
    evaluate,
    leaf_count,
    parse_tree,
    tree_to_json,
)

__all__ = [
    "ENDPOINTS",
    "CheckContext",
    "CheckDefinitionError",
    "Endpoint",
    "Evaluation",
    "EvaluationError",
    "Group",
    "Leaf",
    "LeafResult",
    "Node",
    "Outcome",
    "ParamSpec",
    "endpoints_used",
    "evaluate",
    "leaf_count",
    "parse_tree",
    "tree_to_json",
]
