"""Target assignment: reaching the session's fixed targets, all of them with the whole fleet,
a named few with any drones, or pairs of them given to particular drones to inspect."""

from __future__ import annotations

import math
import random
from collections.abc import Sequence

from benchmark.authoring.templates.base import (
    SessionView,
    TaskDraft,
    Template,
    TemplateUnfit,
    all_of,
    leaf,
    pick,
)
from benchmark.authoring.templates.common import diagonal_m as _diagonal_m
from benchmark.authoring.templates.common import target_xy as _xy
from emulator.world import Target

__all__ = ["TEMPLATES"]


def _fixed(view: SessionView, k: int) -> list[Target]:
    fixed = [t for t in view.points if t.kind == "fixed"]
    if len(fixed) < k:
        raise TemplateUnfit(f"needs {k} fixed targets, the session has {len(fixed)}")
    return fixed


def _greedy_tour_m(start: Sequence[float], targets: Sequence[Target]) -> float:
    """Length of a nearest-neighbour tour from start through every target."""
    here, left, total = (start[0], start[1]), list(targets), 0.0
    while left:
        t = min(left, key=lambda t: math.dist(here, t.position_m[:2]))
        total += math.dist(here, t.position_m[:2])
        here = (t.position_m[0], t.position_m[1])
        left.remove(t)
    return total


def _pairs(targets: list[Target]) -> list[tuple[Target, Target]]:
    """Pairs of near targets: the first left with its nearest remaining neighbour."""
    left, pairs = list(targets), []
    while left:
        a = left.pop(0)
        b = min(left, key=lambda t: math.dist(a.position_m[:2], t.position_m[:2]))
        left.remove(b)
        pairs.append((a, b))
    return pairs


def _visit_all_targets(view: SessionView, rng: random.Random) -> TaskDraft:
    targets, fleet = view.points, view.drones
    alt = view.cruise_altitude(rng)
    listed = "; ".join(f"{t.name} at {_xy(t)}" for t in targets)
    start = fleet[0].position_m
    share_m = 2.0 * _greedy_tour_m(start, targets) / len(fleet)
    longest_m = max(math.dist(start[:2], t.position_m[:2]) for t in targets)
    return TaskDraft(
        phrasings=[
            f"Complete the target assignment with the whole fleet: share the session's "
            f"{len(targets)} targets out among all drones and fly over them until at least 95 % "
            f"of the targets have been reached. The targets are: {listed}.",
            f"Use every drone to reach the {len(targets)} targets of this session ({listed}); "
            f"the task is done once 95 % of them or more have been reached.",
            f"Divide these {len(targets)} targets among all the drones and visit them, aiming "
            f"for at least 95 % reached: {listed}.",
        ],
        checks=all_of(leaf("task_progress", expected_progress=0.95)),
        oracle=[[{"op": "visit_targets", "drones": [d.id for d in fleet],
                  "targets": [t.id for t in targets], "altitude_m": alt}]],
        flight_m=_diagonal_m(view) + max(share_m, longest_m),
        steps=len(fleet) + len(targets),
    )


def _reach_three(view: SessionView, rng: random.Random) -> TaskDraft:
    chosen = pick(rng, _fixed(view, 3), 3)
    team = pick(rng, view.drones, min(3, len(view.drones)))
    alt = view.cruise_altitude(rng)
    listed = (f"{chosen[0].name} at {_xy(chosen[0])}, {chosen[1].name} at {_xy(chosen[1])} "
              f"and {chosen[2].name} at {_xy(chosen[2])}")
    return TaskDraft(
        phrasings=[
            f"Make sure three targets are reached: {listed}. Any drones may do it, one or "
            f"several, as long as each target is flown over by at least one drone.",
            f"Reach each of {listed} with whichever drones you prefer.",
            f"Three targets need a visit from at least one drone each: {listed}. Pick the "
            f"drones yourself.",
        ],
        checks=all_of(*(leaf("target_is_reached", target_id=t.id) for t in chosen)),
        oracle=[[{"op": "visit_targets", "drones": [d.id for d in team],
                  "targets": [t.id for t in chosen], "altitude_m": alt}]],
        flight_m=_diagonal_m(view) + _greedy_tour_m(team[0].position_m, chosen),
        steps=len(team) + 3,
    )


def _split_inspection(view: SessionView, rng: random.Random) -> TaskDraft:
    team = pick(rng, view.drones, 3)
    pairs = _pairs(pick(rng, _fixed(view, 6), 6))
    alt = view.cruise_altitude(rng)
    duties = [(d, *sorted(pair, key=lambda t: math.dist(d.position_m[:2], t.position_m[:2])))
              for d, pair in zip(team, pairs, strict=True)]
    listed = "; ".join(f"{d.name} takes {a.name} at {_xy(a)} and {b.name} at {_xy(b)}"
                       for d, a, b in duties)
    checks, ops = [], []
    for d, a, b in duties:
        checks += [leaf("target_is_reached_by_drone", target_id=t.id, drone_id=d.id)
                   for t in (a, b)]
        checks += [leaf("target_in_photo_taken_by_drone", drone_id=d.id, target_id=t.id)
                   for t in (a, b)]
        for t in (a, b):
            ops += [{"op": "reach", "drone": d.id, "target": t.id, "altitude_m": alt},
                    {"op": "photo", "drone": d.id}]
    flight_m = max(_greedy_tour_m(d.position_m, (a, b)) for d, a, b in duties)
    return TaskDraft(
        phrasings=[
            f"Split the inspection of six targets among three drones: {listed}. Each drone "
            f"flies over both of its targets and photographs each one from above.",
            f"Inspection duty, two targets per drone ({listed}): reach every assigned target "
            f"and take a picture of it while overhead.",
            f"Assigned inspections: {listed}. For each target, the drone it belongs to must "
            f"fly over it and capture a photo of it.",
        ],
        checks=all_of(*checks),
        oracle=[ops],
        flight_m=flight_m + 0.5 * _diagonal_m(view),
        steps=3 * 5,
    )


TEMPLATES = (
    Template("visit_all_targets", "multi_drone_coordination", "hard", _visit_all_targets,
             point_targets=1, families=("target_assignment",)),
    Template("reach_three", "search", "medium", _reach_three, point_targets=3),
    Template("split_inspection", "multi_drone_coordination", "hard", _split_inspection,
             drones=3, point_targets=6),
)
