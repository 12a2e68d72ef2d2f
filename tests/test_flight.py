"""Flight logic and dynamics, on the pure core (no sockets): timing, obstacles, failsafes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from emulator.flight.autopilot import CommandRefused
from emulator.flight.battery import BATTERY_CRITICAL
from emulator.flight.fleet import Fleet
from emulator.flight.modes import FlightMode, LandedState
from emulator.scenario import Scenario
from emulator.world import Obstacle, World
from tests.scenario_fixtures import tiny_scenario, vehicle


def _fleet(n: int = 1, obstacles: tuple[Obstacle, ...] = (), physics_hz: float = 50.0) -> Fleet:
    specs = [vehicle(k + 1, x=10.0 * k) for k in range(n)]
    return Fleet(tiny_scenario(specs, obstacles=obstacles), physics_hz=physics_hz)


def _run_until_idle(fleet: Fleet, limit_s: float = 2000.0, fast_forward: bool = True) -> float:
    start = fleet.now_s
    while fleet.any_busy:
        fleet.run(500, fast_forward=fast_forward)
        assert fleet.now_s - start < limit_s, "vehicle never finished its goal"
    return fleet.now_s - start


def _airborne(fleet: Fleet, altitude_m: float = 10.0) -> None:
    for ap in fleet.autopilots:
        ap.arm()
        ap.takeoff(altitude_m)
    _run_until_idle(fleet)


def test_takeoff_takes_the_time_the_climb_rate_implies():
    fleet = _fleet()
    ap = fleet.autopilots[0]
    ap.arm()
    ap.takeoff(10.0)
    assert ap.mode is FlightMode.TAKEOFF and ap.landed_state is LandedState.TAKEOFF
    elapsed = _run_until_idle(fleet)
    climb, accel = ap.params["MPC_TKO_SPEED"], ap.params["MPC_ACC_UP_MAX"]
    expected = 10.0 / climb + climb / accel  # cruise at the climb rate, plus ramp up and down
    assert elapsed == pytest.approx(expected, rel=0.05)
    assert ap.position_m[2] == pytest.approx(10.0, abs=0.05)
    assert ap.mode is FlightMode.HOLD and ap.landed_state is LandedState.IN_AIR


def test_500_m_goto_takes_what_cruise_speed_and_acceleration_imply():
    fleet = _fleet()
    _airborne(fleet)
    ap = fleet.autopilots[0]
    ap.reposition((500.0, 0.0, 10.0))
    elapsed = _run_until_idle(fleet)
    speed, accel = ap.params["MPC_XY_CRUISE"], ap.params["MPC_ACC_HOR"]
    assert elapsed == pytest.approx(500.0 / speed + speed / accel, rel=0.03)
    x, y, z = ap.position_m
    assert math.dist((x, y, z), (500.0, 0.0, 10.0)) < 0.1
    # Never a jump: consecutive recorded samples are at most one step of max speed apart.
    traj = fleet.recorder.trajectory("d1")
    steps = np.linalg.norm(np.diff(traj[:, 1:4], axis=0), axis=1)
    assert steps.max() <= ap.params["MPC_XY_VEL_MAX"] * fleet.dt_s * 1.01


def test_fast_forward_gives_the_same_trajectory_as_stepping():
    results = []
    for fast in (False, True):
        fleet = _fleet(n=3)
        for ap in fleet.autopilots:
            ap.arm()
            ap.takeoff(15.0)
        _run_until_idle(fleet, fast_forward=fast)
        for k, ap in enumerate(fleet.autopilots):
            ap.reposition((300.0 + 50 * k, 100.0, 25.0))
        _run_until_idle(fleet, fast_forward=fast)
        results.append((fleet.now_s, [fleet.recorder.trajectory(f"d{k + 1}") for k in range(3)]))
    (t_slow, slow), (t_fast, fast_) = results
    assert t_slow == t_fast
    for a, b in zip(slow, fast_, strict=True):
        assert a.shape == b.shape
        assert np.abs(a - b).max() < 1e-6


def test_path_through_an_obstacle_stops_short_and_holds():
    wall = Obstacle.disc("o1", "tower", (100.0, 0.0), 10.0, height_m=0.0)
    fleet = _fleet(obstacles=(wall,))
    _airborne(fleet)
    ap = fleet.autopilots[0]
    ap.reposition((200.0, 0.0, 10.0))
    _run_until_idle(fleet)
    x, y, _ = ap.position_m
    gap = math.hypot(x - 100.0, y) - 10.0
    assert gap == pytest.approx(fleet.world.safety_margin_m, abs=0.05)
    assert ap.mode is FlightMode.HOLD
    stops = fleet.recorder.events("d1", kinds=["obstacle_stop"])
    assert len(stops) == 1 and stops[0].data["obstacle"] == "o1"
    # The trajectory never entered the obstacle.
    traj = fleet.recorder.trajectory("d1")
    assert (np.hypot(traj[:, 1] - 100.0, traj[:, 2]) > 10.0).all()


def test_capped_obstacle_is_overflown_above_its_height():
    block = Obstacle.disc("o1", "shed", (100.0, 0.0), 10.0, height_m=15.0)
    fleet = _fleet(obstacles=(block,))
    _airborne(fleet, altitude_m=30.0)
    ap = fleet.autopilots[0]
    ap.reposition((200.0, 0.0, 30.0))
    _run_until_idle(fleet)
    assert ap.position_m[0] == pytest.approx(200.0, abs=0.1)
    assert not fleet.recorder.events("d1", kinds=["obstacle_stop"])


def test_rtl_climbs_returns_lands_and_disarms():
    fleet = _fleet()
    _airborne(fleet)
    ap = fleet.autopilots[0]
    ap.reposition((200.0, 150.0, 10.0))
    _run_until_idle(fleet)
    ap.return_to_launch()
    assert ap.mode is FlightMode.RTL
    _run_until_idle(fleet)
    traj = fleet.recorder.trajectory("d1")
    assert traj[:, 3].max() >= ap.params["RTL_RETURN_ALT"] - 0.1
    assert math.hypot(*ap.position_m[:2]) < 0.5 and ap.position_m[2] == 0.0
    assert not ap.armed and not ap.in_air
    kinds = [e.kind for e in fleet.recorder.events("d1")]
    assert kinds.index("landed") < kinds.index("disarm")


def test_refusals_change_nothing():
    fleet = _fleet()
    ap = fleet.autopilots[0]
    with pytest.raises(CommandRefused, match="arm first"):
        ap.takeoff(10.0)
    with pytest.raises(CommandRefused, match="on the ground"):
        ap.reposition((10.0, 0.0, 10.0))
    ap.arm()
    with pytest.raises(CommandRefused, match="exceeds ceiling"):
        ap.takeoff(900.0)
    assert ap.mode is FlightMode.HOLD and not ap.in_air
    assert not fleet.any_busy
    _airborne(fleet)
    with pytest.raises(CommandRefused, match="in the air"):
        ap.disarm()
    with pytest.raises(CommandRefused, match="geofence"):
        ap.reposition((50_000.0, 0.0, 10.0))
    assert ap.armed and fleet.dyn.goal_m[0].tolist() == pytest.approx([0.0, 0.0, 10.0], abs=0.05)


def test_critical_battery_returns_home_and_emergency_lands():
    fleet = _fleet()
    _airborne(fleet)
    ap = fleet.autopilots[0]
    ap.reposition((300.0, 0.0, 10.0))
    _run_until_idle(fleet)
    fleet.bat.pct[0] = ap.params["BAT_CRIT_THR"] * 100.0 + 0.05
    for _ in range(100):  # hovering is no goal: step the clock explicitly
        fleet.step()
    assert fleet.bat.level[0] == BATTERY_CRITICAL
    assert ap.mode is FlightMode.RTL
    assert fleet.recorder.events("d1", kinds=["failsafe"])[0].data["reason"] == "battery_critical"
    fleet.bat.pct[0] = ap.params["BAT_EMERGEN_THR"] * 100.0 + 0.05
    _run_until_idle(fleet)
    reasons = [e.data["reason"] for e in fleet.recorder.events("d1", kinds=["failsafe"])]
    assert reasons == ["battery_critical", "battery_emergency"]
    assert not ap.in_air
    assert math.hypot(*ap.position_m[:2]) > 50.0  # landed where it was, not at home


def test_battery_drains_more_with_speed_and_headwind():
    def drain(wind_from_deg: float, speed: float) -> float:
        from emulator.world import Wind

        world = World(wind=Wind(6.0, wind_from_deg))
        fleet = Fleet(Scenario("t", "others", world, (vehicle(1),), "t"))
        ap = fleet.autopilots[0]
        ap.set_param("MPC_XY_CRUISE", speed)
        ap.arm()
        ap.takeoff(10.0)
        _run_until_idle(fleet)
        before = ap.battery_pct
        ap.reposition((0.0, 600.0, 10.0))  # fly north
        _run_until_idle(fleet)
        return before - ap.battery_pct

    headwind, tailwind = drain(0.0, 8.0), drain(180.0, 8.0)
    assert headwind > tailwind * 1.2


def test_mission_items_are_reached_in_order_and_complete():
    from emulator.flight.mission import Cmd, MissionItem

    fleet = _fleet()
    ap = fleet.autopilots[0]
    origin = fleet.world.origin
    items = []
    for seq, (x, y) in enumerate([(50.0, 0.0), (50.0, 50.0), (0.0, 50.0)]):
        lat, lon, _ = origin.to_geodetic(x, y, 0.0)
        items.append(MissionItem(seq=seq, frame=6, command=Cmd.NAV_WAYPOINT,
                                 x=round(lat * 1e7), y=round(lon * 1e7), z=20.0))
    ap.mission.replace(items)
    ap.mission.enter_mission_mode()
    ap.arm()
    _run_until_idle(fleet)
    reached = [e.data["item"] for e in fleet.recorder.events("d1", kinds=["mission_item_reached"])]
    assert reached == [0, 1, 2]
    assert fleet.recorder.events("d1", kinds=["mission_complete"])
    assert math.dist(ap.position_m, (0.0, 50.0, 20.0)) < 0.5
    # The trajectory passed close to every waypoint.
    traj = fleet.recorder.trajectory("d1")
    for x, y in [(50.0, 0.0), (50.0, 50.0)]:
        assert np.hypot(traj[:, 1] - x, traj[:, 2] - y).min() <= ap.params["NAV_ACC_RAD"] + 0.1
