"""The autopilot's explicit state (emulator.flight.vehicle_state): the take-off, landing and
RTL sequences and the mission's items step through their phases as the physics reports each
goal reached; timers name what they do; and nothing outside a class reaches into the private
members of the autopilot or its parts."""

from __future__ import annotations

import ast
import math
from pathlib import Path

import pytest

from emulator.flight.autopilot import Autopilot
from emulator.flight.fleet import Fleet
from emulator.flight.mission import Cmd, MissionItem
from emulator.flight.modes import FlightMode, LandedState
from emulator.flight.operator import place_on_ground
from emulator.flight.vehicle_state import Phase, TimerAction
from emulator.world import Obstacle
from tests.cli_fixtures import ROOT
from tests.scenario_fixtures import tiny_scenario, vehicle


def _fleet(*obstacles: Obstacle) -> tuple[Fleet, Autopilot]:
    fleet = Fleet(tiny_scenario([vehicle(1)], obstacles=obstacles))
    return fleet, fleet.autopilots[0]


def _phases_until(fleet: Fleet, ap: Autopilot, done, limit_s: float = 600.0) -> list[Phase]:
    """Every phase the vehicle passes through, stepping until done() (or failing)."""
    seen = [ap.phase]
    start = fleet.now_s
    while not done():
        fleet.step()
        if ap.phase is not seen[-1]:
            seen.append(ap.phase)
        assert fleet.now_s - start < limit_s, f"not done; phases so far {seen}"
    return seen


def _airborne_at(fleet: Fleet, ap: Autopilot, target_m: tuple[float, float, float]) -> None:
    ap.arm()
    ap.takeoff(target_m[2])
    assert _phases_until(fleet, ap, lambda: not fleet.busy[0]) == [Phase.TAKING_OFF, Phase.IDLE]
    assert ap.mode is FlightMode.HOLD and ap.landed_state is LandedState.IN_AIR
    ap.reposition(target_m)
    _phases_until(fleet, ap, lambda: not fleet.busy[0])


def test_rtl_climbs_returns_descends_and_lands_phase_by_phase() -> None:
    fleet, ap = _fleet()
    _airborne_at(fleet, ap, (120.0, 40.0, 10.0))
    ap.return_to_launch()
    assert ap.mode is FlightMode.RTL and ap.phase is Phase.CLIMBING_TO_RTL
    phases = _phases_until(fleet, ap, lambda: not ap.in_air)
    assert phases == [Phase.CLIMBING_TO_RTL, Phase.RETURNING, Phase.DESCENDING, Phase.LANDING,
                      Phase.IDLE]
    x, y, z = ap.position_m
    assert math.hypot(x, y) < 1.0 and z == 0.0
    # touchdown: on the ground, the auto-disarm timer set, then disarmed and back in HOLD
    assert ap.landed_state is LandedState.ON_GROUND
    assert ap.state.timer is TimerAction.AUTO_DISARM
    _phases_until(fleet, ap, lambda: not ap.armed, limit_s=5.0)
    assert ap.state.timer is TimerAction.NONE and ap.mode is FlightMode.HOLD


def test_rtl_above_the_return_altitude_flies_home_at_once() -> None:
    fleet, ap = _fleet()
    _airborne_at(fleet, ap, (60.0, 0.0, 40.0))
    ap.return_to_launch()
    assert ap.phase is Phase.RETURNING and ap.state.land_at_m == (0.0, 0.0)


def test_landing_at_a_point_approaches_it_first() -> None:
    fleet, ap = _fleet()
    _airborne_at(fleet, ap, (0.0, 0.0, 20.0))
    ap.land((30.0, 0.0))
    assert ap.mode is FlightMode.LAND
    phases = _phases_until(fleet, ap, lambda: not ap.in_air)
    assert phases == [Phase.APPROACHING_LANDING, Phase.DESCENDING, Phase.LANDING, Phase.IDLE]
    assert abs(ap.position_m[0] - 30.0) < 1.0


def test_an_obstacle_on_the_way_home_ends_the_sequence_in_hold() -> None:
    wall = Obstacle.disc("o1", "Mast", (60.0, 0.0), 5.0)  # height 0: every altitude
    fleet, ap = _fleet(wall)
    _airborne_at(fleet, ap, (50.0, 30.0, 40.0))
    ap.reposition((100.0, 0.0, 40.0))  # around the mast: home is behind it now
    _phases_until(fleet, ap, lambda: not fleet.busy[0])
    ap.return_to_launch()
    assert ap.phase is Phase.RETURNING and ap.state.blockage is not None
    _phases_until(fleet, ap, lambda: ap.mode is FlightMode.HOLD)
    assert ap.phase is Phase.IDLE and ap.state.blockage is None and ap.in_air
    assert [e.kind for e in fleet.recorder.events("d1", kinds=("obstacle_stop",))] == [
        "obstacle_stop"]


def test_failures_land_or_fall_through_their_phases() -> None:
    fleet, ap = _fleet()
    _airborne_at(fleet, ap, (30.0, 0.0, 20.0))
    ap.failures.fail("gps", "test")  # no position: PX4 lands where it is
    assert ap.mode is FlightMode.LAND
    assert _phases_until(fleet, ap, lambda: not ap.in_air) == [
        Phase.DESCENDING, Phase.LANDING, Phase.IDLE]
    fleet, ap = _fleet()
    _airborne_at(fleet, ap, (30.0, 0.0, 20.0))
    ap.failures.fail("motor", "test")  # comes down at once, faster than a landing
    assert ap.phase is Phase.FALLING and ap.landed_state is LandedState.LANDING
    assert _phases_until(fleet, ap, lambda: not ap.in_air) == [Phase.FALLING, Phase.IDLE]


def test_arming_without_take_off_sets_the_preflight_timer() -> None:
    fleet, ap = _fleet()
    ap.arm()
    assert ap.state.timer is TimerAction.PREFLIGHT_DISARM and not fleet.busy[0]
    ap.takeoff(5.0)  # leaving the ground cancels it
    assert ap.state.timer is TimerAction.NONE and ap.phase is Phase.TAKING_OFF


def _item(fleet: Fleet, seq: int, command: int, x_m: float, y_m: float, z_m: float,
          param1: float = 0.0) -> MissionItem:
    lat, lon, _ = fleet.world.origin.to_geodetic(x_m, y_m, 0.0)
    return MissionItem(seq, 6, command, param1, 0.0, 0.0, math.nan, round(lat * 1e7),
                       round(lon * 1e7), z_m)


def test_mission_items_are_phases_and_their_holds_timers() -> None:
    fleet, ap = _fleet()
    ap.mission.replace([_item(fleet, 0, Cmd.NAV_WAYPOINT, 40.0, 0.0, 15.0, param1=5.0),
                        _item(fleet, 1, Cmd.NAV_LOITER_UNLIM, 40.0, 40.0, 15.0)])
    ap.set_mode(FlightMode.MISSION)
    ap.arm()
    assert ap.phase is Phase.MISSION_CLIMB
    phases = _phases_until(fleet, ap, lambda: ap.state.timer is TimerAction.MISSION_NEXT)
    assert phases == [Phase.MISSION_CLIMB, Phase.MISSION_WAYPOINT, Phase.IDLE]
    assert ap.state.timer_seq == 0 and fleet.busy[0]  # holding 5 s at item 0
    ap.hold()  # a paused mission's hold must not fire later
    assert ap.state.timer is TimerAction.NONE and ap.mission.active is False
    ap.set_mode(FlightMode.MISSION)  # resumes item 0, then on to the loiter
    phases = _phases_until(fleet, ap, lambda: ap.mission.current == 1 and not fleet.busy[0])
    assert Phase.MISSION_LOITER_UNLIMITED in phases and ap.phase is Phase.IDLE
    reached = [e.data["item"] for e in fleet.recorder.events("d1", kinds=("mission_item_reached",))]
    assert reached == [0, 0, 1]


def test_an_operator_reset_drops_the_sequence() -> None:
    fleet, ap = _fleet()
    _airborne_at(fleet, ap, (50.0, 0.0, 10.0))
    ap.return_to_launch()
    assert ap.phase is Phase.CLIMBING_TO_RTL
    place_on_ground(ap, 5.0, 5.0)
    assert ap.phase is Phase.IDLE and not ap.state.goal_pending and not fleet.busy[0]
    assert ap.mode is FlightMode.HOLD and ap.landed_state is LandedState.ON_GROUND


# -------------------------------------------------------------- encapsulation
_OWNERS = {  # module -> classes whose private members stay inside them
    "emulator/flight/vehicle.py": ("Vehicle",),
    "emulator/flight/autopilot.py": ("Autopilot",),
    "emulator/flight/autopilot_mission.py": ("MissionRunner",),
    "emulator/flight/offboard.py": ("OffboardControl",),
    "emulator/flight/failures.py": ("VehicleFailures",),
}
_PACKAGES = ("emulator", "mavlink_gateway", "swarm_agents", "benchmark", "mqtt_bus", "console",
             "mavswarm", "tests", "perf")


def _private_members() -> set[str]:
    names: set[str] = set()
    for module, classes in _OWNERS.items():
        for node in ast.walk(ast.parse((ROOT / module).read_text())):
            if isinstance(node, ast.ClassDef) and node.name in classes:
                for inner in ast.walk(node):
                    if isinstance(inner, ast.FunctionDef):
                        names.add(inner.name)
                    elif (isinstance(inner, ast.Attribute) and isinstance(inner.value, ast.Name)
                          and inner.value.id == "self"):
                        names.add(inner.attr)
    return {n for n in names if n.startswith("_") and not n.startswith("__")}


def _reaches_in(path: Path, private: set[str]) -> list[str]:
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Attribute) and node.attr in private:
            receiver = node.value
            if isinstance(receiver, ast.Name) and receiver.id in ("self", "cls", *(
                c for classes in _OWNERS.values() for c in classes
            )):
                continue
            found.append(f"{path.relative_to(ROOT)}:{node.lineno}: {ast.unparse(node)}")
    return found


@pytest.mark.slow
def test_no_module_uses_a_private_member_of_the_autopilot_or_its_parts() -> None:
    private = _private_members()
    assert {"_set_goal", "_stopped_by", "_setpoint", "_ap"} <= private
    found = [hit for package in _PACKAGES for path in sorted((ROOT / package).rglob("*.py"))
             if ".venv" not in path.parts and "node_modules" not in path.parts
             for hit in _reaches_in(path, private)]
    assert not found, "\n".join(found)
