"""What the MultiUAV-Plat reference answers, recorded from its specification
(`../shared/spec/entities.md`, `commands.md`, `perception_and_roles.md`): the fields of each
record and response, per route group. The compatibility tests run request sequences against
`mavswarm serve` and compare status codes and shapes with these."""

from __future__ import annotations

from typing import Any

__all__ = ["COMMAND_KEYS", "COMMAND_RECORD_KEYS", "DRONE_KEYS", "ENVIRONMENT_KEYS",
           "HISTORY_KEYS", "LAND_ALL_DETAIL_KEYS", "LAND_ALL_KEYS", "OBSTACLE_KEYS",
           "PROGRESS_KEYS", "SESSION_DATA_KEYS", "STATUS_RECORD_KEYS", "TARGET_KEYS",
           "TASK_KEYS", "missing"]

# entities.md 2.1 (battery_volume included: the model's record)
DRONE_KEYS = frozenset({
    "id", "name", "model", "status", "position", "heading", "speed", "perceived_radius",
    "task_radius", "battery_level", "battery_volume", "battery_capacity", "max_speed",
    "max_altitude", "home_position", "created_at", "last_updated"})

# entities.md 3.2
TARGET_KEYS = frozenset({
    "id", "name", "type", "position", "description", "radius", "vertices", "velocity",
    "moving_path", "moving_duration", "charge_amount", "current_path_index", "path_direction",
    "time_in_direction", "movement_mode", "calculated_speed", "last_motion_update",
    "last_tracked_at", "is_reached", "reached_by", "created_at", "last_updated"})

# entities.md 4.1
OBSTACLE_KEYS = frozenset({
    "id", "name", "type", "position", "description", "radius", "width", "length", "vertices",
    "height", "area", "created_at", "last_updated"})

# entities.md 5
ENVIRONMENT_KEYS = frozenset({
    "id", "name", "weather", "temperature", "humidity", "pressure", "wind_speed",
    "wind_direction", "visibility", "created_at", "last_updated"})

# commands.md 1.1
COMMAND_KEYS = frozenset({"command_id", "drone_id", "command", "status", "message",
                          "timestamp"})

# entities.md 6.4
COMMAND_RECORD_KEYS = frozenset({"command_id", "drone_id", "command", "parameters", "status",
                                 "message", "timestamp"})
STATUS_RECORD_KEYS = frozenset({"status", "position", "battery_level", "battery_volume",
                                "timestamp"})
HISTORY_KEYS = frozenset({"command_history", "status_history", "path_history",
                          "target_reaches", "moving_target_tracking", "area_coverage"})

# entities.md 8
SESSION_DATA_KEYS = frozenset({
    "id", "name", "description", "status", "creator", "task_type", "task_description",
    "is_distance_3d", "canvas_width", "canvas_height", "created_at", "last_updated",
    "statistics", "drones", "targets", "obstacles", "environment", "tasks", "history"})

# entities.md 6.3
PROGRESS_KEYS = frozenset({"task_type", "progress_percentage", "is_completed",
                           "status_message", "details", "target_reach_summary",
                           "area_coverage_summary"})

# entities.md 7
TASK_KEYS = frozenset({
    "id", "name", "content", "content_aliases", "description", "creator", "originated_from",
    "difficulty", "related_apis", "execution_check_apis", "commands", "is_done", "is_passed",
    "created_at", "last_updated"})

# commands.md 11
LAND_ALL_KEYS = frozenset({"message", "total_drones", "drones_landed", "drones_blocked",
                           "drones_already_grounded", "details"})
LAND_ALL_DETAIL_KEYS = frozenset({"drone_id", "drone_name", "previous_status",
                                  "previous_altitude", "new_status", "new_altitude", "action",
                                  "reason"})


def missing(expected: frozenset[str], record: Any) -> set[str]:
    """The expected keys a record lacks (all of them for a record that is not an object)."""
    if not isinstance(record, dict):
        return set(expected)
    return set(expected) - set(record)
