"""The gateway's flight primitives against the real emulator over real UDP (MAVSDK).

Every test starts a stepped swarm, connects a Gateway to it and checks each primitive's
outcome (status, message, reported state) against the emulator's ground truth: the recorded
trajectory, the truth events and the autopilots' state. Each refusal must change nothing.
"""

from __future__ import annotations

import asyncio
import math

import numpy as np
import pytest

from emulator.geo import wrap_heading_deg
from emulator.world import Obstacle
from mavlink_gateway import Status
from mavlink_gateway.flight import ARRIVAL_M
from tests.gateway_fixtures import (
    assert_consistent,
    expect_refusal,
    gateway_session,
    near,
    no_teleport,
    truth,
)
from tests.scenario_fixtures import tiny_scenario, vehicle

pytestmark = pytest.mark.mavsdk

def _kinds(s, drone: str, t0_s: float) -> list[str]:
    return [e.kind for e in s.swarm.recorder.events(drone, t0_s=t0_s)]


async def test_take_off_and_land_fly_in_simulated_time():
    # Default telemetry rates here (the other tests run faster ones to wait less).
    sc = tiny_scenario([vehicle(1), vehicle(2, 10.0, 0.0)])
    async with gateway_session(sc, telemetry_hz=None) as s:
        gw, ap = s.gw, s.ap("d1")
        await expect_refusal(s, gw.land("d1"), "land refused: drone d1 is on the ground")

        t0 = s.now_s
        out = await gw.take_off("d1", 12)
        assert out.status is Status.OK and out.message == "d1 took off to 12.0 m"
        assert_consistent(s, out, "d1")
        assert out.state.flight_state == "hovering" and out.state.armed
        assert ap.armed and ap.in_air
        near(s, "d1", (0.0, 0.0, 12.0))
        # It climbed at the take-off rate (no teleport), never above its goal, and never sank
        # by more than the millimetre it settles by once there.
        assert s.now_s - t0 >= 12.0 / ap.params["MPC_TKO_SPEED"]
        kinds = _kinds(s, "d1", t0)
        assert kinds.index("arm") < kinds.index("takeoff") < kinds.index("takeoff_complete")
        climb = s.swarm.recorder.trajectory("d1", t0)
        assert climb[:, 3].max() <= 12.05 and (np.diff(climb[:, 3]) >= -1e-3).all()
        no_teleport(s, "d1", t0)
        # The other drone did not move.
        assert truth(s, "d2").position_m == (10.0, 0.0, 0.0) and not s.ap("d2").armed

        await expect_refusal(s, gw.take_off("d1", 20), "take_off refused: drone d1 is already "
                             "in the air")

        t1 = s.now_s
        out = await gw.land("d1")
        assert out.status is Status.OK and out.message == "d1 landed at (0.0, 0.0)"
        assert_consistent(s, out, "d1")
        assert out.state.flight_state == "on_ground"
        assert ap.position_m[2] == 0.0 and not ap.in_air
        near(s, "d1", (0.0, 0.0, 0.0), 0.5)
        slow = ap.params["MPC_LAND_ALT2"]
        assert s.now_s - t1 >= (12.0 - slow) / ap.params["MPC_Z_VEL_MAX_DN"] \
            + slow / ap.params["MPC_LAND_SPEED"]
        await s.settle()
        assert not ap.armed
        kinds = _kinds(s, "d1", t1)
        assert kinds.index("landed") < kinds.index("disarm")
        state = gw.drone_state("d1")
        assert state.ok and state.state.flight_state == "on_ground" and not state.state.armed
        assert state.message.startswith("d1 on_ground at (0.0, 0.0, 0.0)")


async def test_take_off_refusals_change_nothing():
    async with gateway_session(tiny_scenario([vehicle(1)])) as s:
        gw = s.gw
        for altitude, reason in [
            (0.5, "altitude 0.5 m is below the 1 m minimum flight altitude"),
            (-5, "altitude -5 m is below the 1 m minimum"),
            (121, "altitude 121 m exceeds this drone's ceiling of 120 m"),
            (math.nan, "altitude must be a finite number, got nan"),
            (math.inf, "altitude must be a finite number, got inf"),
            ("10", "altitude must be a finite number, got '10'"),
            (True, "altitude must be a finite number, got True"),
            (None, "altitude must be a finite number, got None"),
            (10**400, "altitude must be a finite number, got 1000"),
        ]:
            await expect_refusal(s, gw.take_off("d1", altitude), f"take_off refused: {reason}")
        await expect_refusal(s, gw.take_off(None, 10), "unknown drone None")
        await expect_refusal(s, gw.take_off(["d1"], 10), "unknown drone ['d1']")
        for name, args in [("take_off", (10,)), ("land", ()), ("move_to", (1, 1, 10)),
                           ("move_towards", (0, 10)), ("change_altitude", (10,)),
                           ("rotate", (0,)), ("hover", (1,)), ("return_home", ()),
                           ("set_home", ()), ("move_along_path", ([[1, 1]],)),
                           ("take_photo", ()), ("charge", ())]:
            await expect_refusal(s, getattr(gw, name)("d9", *args),
                                 "unknown drone 'd9' (known: d1)")
        for name, args in [("drone_state", ()), ("nearby", ()), ("read_messages", ()),
                           ("broadcast", ("hi",)), ("send_message", ("d1", "hi"))]:
            await expect_refusal(s, lambda n=name, a=args: getattr(gw, n)("d9", *a),
                                 "unknown drone 'd9' (known: d1)")

        s.services.operator_reset_batteries(9.0)
        await s.settle()
        await expect_refusal(s, gw.take_off("d1", 10),
                             "take_off refused: battery 9% is too low to take off")

        # Every other flight primitive needs the drone in the air.
        for name, call in [
            ("move_to", gw.move_to("d1", 10, 10, 10)),
            ("move_towards", gw.move_towards("d1", 90, 10)),
            ("change_altitude", gw.change_altitude("d1", 20)),
            ("rotate", gw.rotate("d1", 90)),
            ("hover", gw.hover("d1", 5)),
            ("move_along_path", gw.move_along_path("d1", [[10, 10]])),
            ("return_home", gw.return_home("d1")),
            ("take_photo", gw.take_photo("d1")),
        ]:
            await expect_refusal(s, call, f"{name} refused: drone d1 is on the ground: "
                                 "take off first")


async def test_move_to_move_towards_and_change_altitude():
    async with gateway_session(tiny_scenario([vehicle(1)])) as s:
        gw, ap = s.gw, s.ap("d1")
        assert (await gw.take_off("d1", 10)).ok

        t0 = s.now_s
        out = await gw.move_to("d1", 40, 30, 15)
        assert out.status is Status.OK and out.message == "d1 reached (40.0, 30.0, 15.0)"
        assert_consistent(s, out, "d1", tolerance_m=ARRIVAL_M)
        near(s, "d1", (40.0, 30.0, 15.0))
        assert s.now_s - t0 >= math.dist((0, 0, 10), (40, 30, 15)) / ap.params["MPC_XY_VEL_MAX"]
        no_teleport(s, "d1", t0)

        out = await gw.move_towards("d1", 90, 20, 5)  # east, and 5 m up
        assert out.status is Status.OK and out.message == "d1 reached (60.0, 30.0, 20.0)"
        near(s, "d1", (60.0, 30.0, 20.0))
        out = await gw.move_towards("d1", 180, 10)  # south, level
        assert out.status is Status.OK and out.message == "d1 reached (60.0, 20.0, 20.0)"
        near(s, "d1", (60.0, 20.0, 20.0))

        t1 = s.now_s
        out = await gw.change_altitude("d1", 30)
        assert out.status is Status.OK and out.message == "d1 reached (60.0, 20.0, 30.0)"
        assert_consistent(s, out, "d1", tolerance_m=ARRIVAL_M)
        near(s, "d1", (60.0, 20.0, 30.0))
        climb = s.swarm.recorder.trajectory("d1", t1)
        assert np.hypot(climb[:, 1] - 60.0, climb[:, 2] - 20.0).max() < 0.5  # straight up
        assert s.now_s - t1 >= 10.0 / ap.params["MPC_Z_VEL_MAX_UP"]

        for call, reason in [
            (gw.move_to("d1", 0, 0, 0.5), "move_to refused: z 0.5 m is below the 1 m minimum"),
            (gw.move_to("d1", 0, 0, 121), "move_to refused: z 121 m exceeds this drone's "
             "ceiling of 120 m"),
            (gw.move_to("d1", 200_000, 0, 10), "move_to refused: x 200000 m is beyond the "
             "100 km map limit"),
            (gw.move_to("d1", 0, 20_000, 10), "move_to refused: (0, 20000) is more than 10 km "
             "from home"),
            (gw.move_to("d1", math.nan, 0, 10), "move_to refused: x must be a finite number"),
            (gw.move_to("d1", 0, "north", 10), "y must be a finite number, got 'north'"),
            (gw.move_towards("d1", 90, 0), "move_towards refused: distance_m must be within "
             "(0, 10000], got 0"),
            (gw.move_towards("d1", 90, -5), "distance_m must be within (0, 10000], got -5"),
            (gw.move_towards("d1", 90, 10_001), "got 10001"),
            (gw.move_towards("d1", math.inf, 10), "heading_deg must be a finite number"),
            (gw.move_towards("d1", 0, 10, -29.5), "move_towards refused: z 0.4"),
            (gw.change_altitude("d1", 0), "change_altitude refused: altitude 0 m is below"),
            (gw.change_altitude("d1", 500), "altitude 500 m exceeds this drone's ceiling"),
            (gw.change_altitude("d1", None), "altitude must be a finite number, got None"),
        ]:
            await expect_refusal(s, call, reason)


async def test_rotate_turns_in_place_at_the_yaw_rate():
    async with gateway_session(tiny_scenario([vehicle(1)])) as s:
        gw, ap = s.gw, s.ap("d1")
        assert (await gw.take_off("d1", 10)).ok
        start = ap.position_m
        dyn = s.swarm.fleet.dyn
        for heading, expected in [(180, 180.0), (-90, 270.0), (450, 90.0)]:
            before, t0 = float(dyn.yaw_deg[0]), s.now_s
            out = await gw.rotate("d1", heading)
            assert out.status is Status.OK and out.message == f"d1 now heads {expected:.0f} deg"
            assert_consistent(s, out, "d1", tolerance_m=0.5)
            turn = abs((expected - before + 180.0) % 360.0 - 180.0)
            assert abs((float(dyn.yaw_deg[0]) - expected + 180.0) % 360.0 - 180.0) < 2.0
            assert s.now_s - t0 >= turn / ap.params["MPC_YAWRAUTO_MAX"] - 0.1
            assert math.dist(ap.position_m, start) < 0.3
            assert abs((out.state.heading_deg - wrap_heading_deg(expected) + 180) % 360 - 180) < 3
        await expect_refusal(s, gw.rotate("d1", math.nan), "rotate refused: heading_deg must be "
                             "a finite number")
        await expect_refusal(s, gw.rotate("d1", "east"), "got 'east'")


async def test_path_visits_every_waypoint_in_order():
    async with gateway_session(tiny_scenario([vehicle(1)])) as s:
        gw = s.gw
        assert (await gw.take_off("d1", 10)).ok
        t0 = s.now_s
        out = await gw.move_along_path("d1", [[30, 0], (30, 30, 20), [0, 30]])
        assert out.status is Status.OK
        assert out.message == "d1 completed a path of 3 waypoints (93 m)"
        assert_consistent(s, out, "d1", tolerance_m=ARRIVAL_M)
        # A waypoint without z keeps the altitude the path started at.
        near(s, "d1", (0.0, 30.0, 10.0))
        reached = [e.data["item"] for e in
                   s.swarm.recorder.events("d1", t0_s=t0, kinds=["mission_item_reached"])]
        assert reached == [0, 1, 2]
        traj = s.swarm.recorder.trajectory("d1", t0)
        closest = []
        for point in [(30, 0, 10), (30, 30, 20), (0, 30, 10)]:
            d = np.linalg.norm(traj[:, 1:4] - point, axis=1)
            assert d.min() <= s.ap("d1").params["NAV_ACC_RAD"] + 0.1, point
            closest.append(int(d.argmin()))
        assert closest == sorted(closest)
        no_teleport(s, "d1", t0)

        for waypoints, reason in [
            ([], "waypoints must be a list of 1 to 100 points"),
            ([[0, 0]] * 101, "waypoints must be a list of 1 to 100 points"),
            (None, "waypoints must be a list of 1 to 100 points"),
            ({"x": 1, "y": 2}, "waypoints must be a list of 1 to 100 points"),
            ([[1]], "waypoint 1 must be [x, y] or [x, y, z], got [1]"),
            ([[0, 0], [1, 2, 3, 4]], "waypoint 2 must be [x, y] or [x, y, z]"),
            ([[0, 0], [0, 0, 500]], "waypoint 2 z 500 m exceeds this drone's ceiling"),
            ([[0, 0, 0.2]], "waypoint 1 z 0.2 m is below the 1 m minimum"),
            ([[0, math.nan]], "waypoint 1 y must be a finite number"),
            ([[300_000, 0]], "waypoint 1 x 300000 m is beyond the 100 km map limit"),
            # Within the map but beyond the autopilot's geofence: the upload is refused.
            ([[20_000, 0]], "the autopilot refused the move_along_path mission: mission item 0:"
             " 20000 m from home"),
        ]:
            await expect_refusal(s, gw.move_along_path("d1", waypoints),
                                 f"move_along_path refused: {reason}")


async def test_obstacles_block_moves_and_paths():
    wall = Obstacle.disc("o-wall", "Wall", (60.0, 0.0), 10.0, height_m=0.0)
    shed = Obstacle.disc("o-shed", "Shed", (0.0, 60.0), 10.0, height_m=15.0)
    async with gateway_session(tiny_scenario([vehicle(1)], obstacles=[wall, shed])) as s:
        gw, ap = s.gw, s.ap("d1")
        margin = s.scenario.world.safety_margin_m
        assert (await gw.take_off("d1", 10)).ok

        t0 = s.now_s
        out = await gw.move_to("d1", 120, 0, 10)
        assert out.status is Status.BLOCKED
        assert out.message == "move_to stopped at (48.0, 0.0, 10.0): obstacle wall ahead: holding"
        assert_consistent(s, out, "d1", tolerance_m=0.5)
        assert ap.position_m[0] == pytest.approx(60.0 - 10.0 - margin, abs=0.1)
        assert ap.mode.name == "HOLD"
        stops = s.swarm.recorder.events("d1", t0_s=t0, kinds=["obstacle_stop"])
        assert [e.data["obstacle"] for e in stops] == ["o-wall"]
        traj = s.swarm.recorder.trajectory("d1", t0)
        assert (np.hypot(traj[:, 1] - 60.0, traj[:, 2]) > 10.0 + margin - 0.1).all()
        # The drone now senses the wall (and only now: it is 48 m from the start).
        assert [o["id"] for o in gw.nearby("d1").data["obstacles"]] == ["o-wall"]

        # Again towards the wall: blocked at once, where it stands. Let the command's ACK reach
        # the gateway only after the STATUSTEXT (as can happen when a goal is blocked within
        # a physics step): the stop must not be missed.
        link = s.link("d1")
        goto = link.action.goto_location

        async def late_ack(*args: float) -> None:
            texts = len(link.status_texts)
            await goto(*args)
            for _ in range(400):
                if len(link.status_texts) > texts:
                    return
                await asyncio.sleep(0.005)

        link.action.goto_location = late_ack
        try:
            out = await asyncio.wait_for(gw.move_to("d1", 120, 0, 10), 10.0)
        finally:
            link.action.goto_location = goto
        assert out.status is Status.BLOCKED and "obstacle wall ahead" in out.message, out
        assert ap.position_m[0] == pytest.approx(60.0 - 10.0 - margin, abs=0.1)

        # A path: its first waypoint is reached, then the wall stops it.
        assert (await gw.move_to("d1", 0, 0, 10)).ok
        out = await gw.move_along_path("d1", [[20, 0], [120, 0]])
        assert out.status is Status.PARTIAL and out.data == {"reached": 1}
        assert out.message == ("reached 1 of 2 waypoints; move_along_path stopped at "
                               "(48.0, 0.0, 10.0): obstacle wall ahead: holding")
        # Stopped before its first waypoint: blocked, nothing reached.
        assert (await gw.move_to("d1", 0, 0, 10)).ok
        out = await gw.move_along_path("d1", [[120, 0]])
        assert out.status is Status.BLOCKED and "obstacle wall ahead" in out.message

        # A capped obstacle blocks below its height and is overflown above it.
        assert (await gw.move_to("d1", 0, 0, 10)).ok
        out = await gw.move_to("d1", 0, 120, 10)
        assert out.status is Status.BLOCKED and "obstacle shed ahead" in out.message
        assert ap.position_m[1] == pytest.approx(60.0 - 10.0 - margin, abs=0.1)
        assert (await gw.change_altitude("d1", 20)).ok
        t1 = s.now_s
        out = await gw.move_to("d1", 0, 120, 20)
        assert out.status is Status.OK
        near(s, "d1", (0.0, 120.0, 20.0))
        assert not s.swarm.recorder.events("d1", t0_s=t1, kinds=["obstacle_stop"])


async def test_timed_hover_holds_position_for_its_duration():
    async with gateway_session(tiny_scenario([vehicle(1)])) as s:
        gw, ap = s.gw, s.ap("d1")
        assert (await gw.take_off("d1", 10)).ok
        start, battery, t0 = ap.position_m, ap.battery_pct, s.now_s
        out = await gw.hover("d1", 20)
        assert out.status is Status.OK and out.message == "d1 hovered 20 s at (0.0, 0.0, 10.0)"
        assert_consistent(s, out, "d1", tolerance_m=0.5)
        assert 20.0 <= s.now_s - t0 <= 21.0
        traj = s.swarm.recorder.trajectory("d1", t0)
        assert np.linalg.norm(traj[:, 1:4] - start, axis=1).max() < 0.3
        # Hovering costs charge: 20 s of a 1200 s hover endurance.
        assert battery - ap.battery_pct == pytest.approx(20.0 / 1200.0 * 100.0, rel=0.1)
        # A second hover waits its own duration too.
        t1 = s.now_s
        assert (await gw.hover("d1", 5)).ok and 5.0 <= s.now_s - t1 <= 6.0

        for duration, reason in [(0, "got 0"), (-1, "got -1"), (3601, "got 3601"),
                                 (math.nan, "duration_s must be a finite number"),
                                 ("5", "got '5'")]:
            await expect_refusal(s, gw.hover("d1", duration), "hover refused: ", reason)


async def test_set_home_then_return_home_lands_there():
    async with gateway_session(tiny_scenario([vehicle(1)])) as s:
        gw, ap = s.gw, s.ap("d1")
        assert (await gw.take_off("d1", 10)).ok
        assert (await gw.move_to("d1", 80, 40, 10)).ok
        t0 = s.now_s
        out = await gw.set_home("d1")
        assert out.status is Status.OK and out.message == "d1 home set to (80.0, 40.0)"
        assert math.dist(ap.home_m, (80.0, 40.0, 0.0)) < ARRIVAL_M
        assert _kinds(s, "d1", t0) == ["home"]

        assert (await gw.move_to("d1", 0, 0, 10)).ok
        t1 = s.now_s
        out = await gw.return_home("d1")
        assert out.status is Status.OK
        assert out.message == "d1 returned home and landed at (80.0, 40.0)"
        assert_consistent(s, out, "d1")
        assert out.state.flight_state == "on_ground"
        near(s, "d1", (80.0, 40.0, 0.0))
        assert not ap.in_air
        # RTL climbed to its return altitude first, and flew there.
        traj = s.swarm.recorder.trajectory("d1", t1)
        assert traj[:, 3].max() >= ap.params["RTL_RETURN_ALT"] - 0.1
        no_teleport(s, "d1", t1)
        await s.settle()
        assert not ap.armed
        await expect_refusal(s, gw.return_home("d1"), "return_home refused: drone d1 is on the "
                             "ground")
        # set_home works on the ground too.
        assert (await gw.set_home("d1")).ok
