"""Where a MultiUAV-Plat value means something else to our physics, the one place it is
turned into our terms; each mapping returns a note saying what it did.

- **Battery capacity.** The reference's battery is a percentage; its `battery_capacity` is a
  size label (60-100 in its example files), not a physical amount, and nothing there drains by
  it. Our vehicles drain a percentage too (`SIM_HOVER_ENDUR` and effort), and the capacity only
  feeds `BAT_CAPACITY`, which BATTERY_STATUS reports in mAh within [100, 100000]. A capacity
  below 100 is read as that label, times 100 mAh (74 -> 7,400 mAh); one above 100,000 is
  clamped. The battery level is unchanged.
- **Home altitude.** The reference puts home at the starting position, altitude included, so a
  drone spawned in the air has its home in the air, and `return_home` teleports there. Our
  home is where a vehicle lands: its altitude is the ground (z = 0).
- **Vehicle limits.** The reference takes any positive `max_speed`, `max_altitude`,
  `perceived_radius` and `task_radius`; ours become the autopilot parameters `MPC_XY_VEL_MAX`,
  `GF_MAX_VER_DIST`, `SIM_SENS_RAD` and `SIM_TASK_RAD`, whose ranges are PX4-like. A value
  outside its parameter's range is flown at the nearest end of the range.
- **Moving targets** move with the reference's velocity, path and bounce rules
  (emulator.target_motion), in simulated time and continuously: where the reference moves them
  once a wall-clock second and puts one back when a step lands inside an obstacle, ours turn
  round where they meet the obstacle, and follow their path exactly (the reference counts a
  waypoint reached within 0.5 m). A note names each moving target whose track meets an
  obstacle.
"""

from __future__ import annotations

from emulator.flight.params import ParamStore

__all__ = ["MAX_CAPACITY_MAH", "MIN_CAPACITY_MAH", "capacity_mah", "home_altitude_m",
           "moving_target_note", "notes_to_show", "within_param"]

MIN_CAPACITY_MAH = 100.0  # the range of PX4's BAT_CAPACITY that the autopilot accepts
MAX_CAPACITY_MAH = 100_000.0
LABEL_MAH = 100.0  # mAh per unit of the reference's capacity label


def capacity_mah(raw: float, where: str) -> tuple[float, str | None]:
    """The battery capacity in mAh for a file's `battery_capacity`, and a note if mapped."""
    if raw < MIN_CAPACITY_MAH:
        mapped = min(raw * LABEL_MAH, MAX_CAPACITY_MAH)
        return max(mapped, MIN_CAPACITY_MAH), (
            f"{where}.battery_capacity {raw:g} is a MultiUAV-Plat size label; flown as "
            f"{max(mapped, MIN_CAPACITY_MAH):g} mAh (the battery level is unchanged)")
    if raw > MAX_CAPACITY_MAH:
        return MAX_CAPACITY_MAH, (f"{where}.battery_capacity {raw:g} mAh is above "
                                  f"{MAX_CAPACITY_MAH:g}; flown as {MAX_CAPACITY_MAH:g} mAh")
    return raw, None


def within_param(raw: float, param: str, field: str, where: str) -> tuple[float, str | None]:
    """A vehicle limit from the file, inside the range of the parameter that flies it, and a
    note if it had to move."""
    definition = ParamStore.definition(param)
    flown = min(max(raw, definition.minimum), definition.maximum)
    if flown == raw:
        return raw, None
    return flown, (f"{where}.{field} {raw:g} is outside {param}'s range "
                   f"[{definition.minimum:g}, {definition.maximum:g}]; flown as {flown:g}")


def home_altitude_m(raw_z_m: float, where: str) -> tuple[float, str | None]:
    """Home's altitude (the ground), and a note when the file put it in the air."""
    if raw_z_m > 0.0:
        return 0.0, (f"{where}.home_position.z {raw_z_m:g} m: home is where the drone lands, "
                     "on the ground below (z = 0)")
    return 0.0, None


def moving_target_note(where: str, mode: str) -> str:
    """The note for a `moving` target whose track meets an obstacle."""
    return (f"{where}: a moving target ({mode} mode) whose track meets an obstacle; it turns "
            "round where it meets it (the reference steps once a wall-clock second and puts it "
            "back after a step into the obstacle)")


def notes_to_show(notes: tuple[str, ...] | list[str], limit: int = 5) -> list[str]:
    """The first `limit` notes and a count of the rest, for a console (`bench import` lists
    them all)."""
    shown = list(notes[:limit])
    if len(notes) > limit:
        shown.append(f"... and {len(notes) - limit} more such notes "
                     "(emulator/reference_mapping.py)")
    return shown
