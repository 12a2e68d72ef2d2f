"""The five scenario families of the benchmark and what kind of targets each one has.

The two area families (``area_search``, ``area_assignment_and_patrol``) have circle and polygon
area targets; ``target_assignment`` has small ``fixed`` targets; ``target_tracking`` has
``moving`` targets (70 %, rounded) and ``fixed`` ones, TRACKING_TARGETS by level;
``resilience`` has the area families' area targets and RESILIENCE_FIXED_TARGETS ``fixed`` ones
(its tasks schedule hidden faults: benchmark.authoring.templates.resilience). Every family also has
its
level's charging stations (``waypoint`` targets).
"""

from __future__ import annotations

from dataclasses import dataclass

from benchmark.authoring.scenarios.levels import level_spec

__all__ = ["FAMILIES", "FAMILY_SPECS", "MOVING_SHARE", "RESILIENCE_FIXED_TARGETS",
           "TRACKING_TARGETS", "FamilySpec", "family_spec", "moving_count", "target_count"]

FAMILIES: tuple[str, ...] = ("area_search", "area_assignment_and_patrol", "target_assignment",
                             "target_tracking", "resilience")
# target_tracking: targets other than charging stations, by level, and the moving share.
TRACKING_TARGETS = {"easy": 4, "intermediate": 6, "moderate": 8, "hard": 10, "extreme": 12}
MOVING_SHARE = 0.7
# resilience: fixed targets by level, beside the level's area targets.
RESILIENCE_FIXED_TARGETS = {"easy": 4, "intermediate": 6, "moderate": 8, "hard": 10,
                            "extreme": 12}


@dataclass(frozen=True, slots=True)
class FamilySpec:
    """How sessions of one family read: title, task type and target names."""

    family: str
    title: str
    task_type: str
    target_name: str
    area_targets: bool


FAMILY_SPECS: dict[str, FamilySpec] = {
    "area_search": FamilySpec("area_search", "Area search", "area_search", "Search Area", True),
    "area_assignment_and_patrol": FamilySpec(
        "area_assignment_and_patrol", "Area assignment and patrol",
        "area_assignment_and_patrol", "Patrol Zone", True),
    "target_assignment": FamilySpec(
        "target_assignment", "Target assignment", "target_assignment", "Target", False),
    "target_tracking": FamilySpec(
        "target_tracking", "Target tracking", "target_tracking", "Target", False),
    "resilience": FamilySpec("resilience", "Resilience", "others", "Search Area", True),
}


def family_spec(family: str) -> FamilySpec:
    """The description of a family; raises ValueError naming an unknown family."""
    if not isinstance(family, str) or family not in FAMILY_SPECS:
        raise ValueError(f"family must be one of {', '.join(FAMILIES)}; got {family!r}")
    return FAMILY_SPECS[family]


def target_count(family: str, level: str) -> int:
    """Targets of a session of this family and level, charging stations included."""
    spec = level_spec(level)
    if family_spec(family).family == "target_tracking":
        return TRACKING_TARGETS[level] + spec.charging_station_count
    if family == "resilience":
        return spec.area_target_count + RESILIENCE_FIXED_TARGETS[level]
    return spec.target_count(family_spec(family).area_targets)


def moving_count(family: str, level: str) -> int:
    """Moving targets of a session of this family and level."""
    if family_spec(family).family != "target_tracking":
        return 0
    return max(1, round(MOVING_SHARE * TRACKING_TARGETS[level]))
