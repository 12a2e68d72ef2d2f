"""The gateway's payload primitives (camera, charger, radio, perception) and the operator's
resets, against the real emulator over real UDP, checked against ground truth."""

from __future__ import annotations

import asyncio
import json
import math
import re

import pytest

from emulator.flight.battery import PHOTO_COST_PCT
from emulator.radio import MAX_TEXT_CHARS
from emulator.world import Obstacle, Target
from mavlink_gateway import Outcome, Status
from tests.gateway_fixtures import (
    assert_consistent,
    expect_refusal,
    gateway_session,
    no_teleport,
)
from tests.scenario_fixtures import tiny_scenario, vehicle

pytestmark = pytest.mark.mavsdk


def _mentions(outcome: Outcome, words: list[str]) -> list[str]:
    text = json.dumps(outcome.to_dict()).lower()
    return [w for w in words if w.lower() in text]


async def test_photos_capture_what_the_sensor_disc_holds():
    near = Target.disc("t-near", "Near Target", "fixed", (150.0, 0.0, 0.0), 3.0)
    far = Target.disc("t-far", "Far Target", "fixed", (400.0, 0.0, 0.0), 3.0)
    async with gateway_session(tiny_scenario([vehicle(1)], targets=[near, far])) as s:
        gw, ap = s.gw, s.ap("d1")
        assert (await gw.take_off("d1", 10)).ok

        battery = ap.battery_pct
        out = await gw.take_photo("d1")
        assert out.status is Status.OK and out.message == "d1 took photo 1 at (0.0, 0.0)"
        assert out.data == {"photo": 1}
        assert_consistent(s, out, "d1")
        photos = s.swarm.recorder.events("d1", kinds=["photo"])
        assert len(photos) == 1 and photos[0].data["targets"] == ()  # nothing in range
        assert battery - ap.battery_pct == pytest.approx(PHOTO_COST_PCT)

        assert (await gw.move_to("d1", 120, 0, 10)).ok
        out = await gw.take_photo("d1")
        assert out.status is Status.OK and out.message == "d1 took photo 2 at (120.0, 0.0)"
        photos = s.swarm.recorder.events("d1", kinds=["photo"])
        assert len(photos) == 2 and photos[1].data["targets"] == ("t-near",)
        assert math.dist(photos[1].data["position_m"], (120.0, 0.0, 10.0)) < 1.0
        # The outcome says nothing about what is in the picture.
        assert not _mentions(out, ["t-near", "t-far", "Near Target", "Far Target"])

        await expect_refusal(s, gw.take_photo("d7"), "unknown drone 'd7' (known: d1)")


async def test_nearby_reports_exactly_the_entities_in_range():
    # d1 at the origin, sensor radius 50 m. Distances are to the geometry, horizontally.
    targets = [
        Target.disc("tg-in", "Inside", "fixed", (30.0, 0.0, 0.0), 2.0),  # 28 m
        Target.disc("tg-edge-out", "Just Outside", "fixed", (53.0, 0.0, 0.0), 2.0),  # 51 m
        Target.disc("tg-part", "Partly Inside Disc", "circle", (0.0, 55.0, 0.0), 8.0),  # 47 m
        # Centre 71 m away but its corner (40, -20) is at 44.7 m: partly inside counts.
        Target.polygon("tg-poly-part", "Partly Inside Field",
                       [(40.0, -40.0), (90.0, -40.0), (90.0, -20.0), (40.0, -20.0)]),
        Target.polygon("tg-poly-out", "Outside Field",  # nearest corner at 67.1 m
                       [(-80.0, 30.0), (-60.0, 30.0), (-60.0, 50.0), (-80.0, 50.0)]),
        Target.disc("tg-station", "Station", "waypoint", (-45.0, -10.0, 0.0), 4.0,
                    charge_rate_pct_s=1.0),  # 42.1 m
    ]
    obstacles = [
        Obstacle.disc("ob-in", "Mast", (0.0, -30.0), 5.0),  # 25 m
        # Centre 57.5 m away, its east edge at 45 m.
        Obstacle.polygon("ob-poly-part", "Barn",
                         [(-70.0, -5.0), (-45.0, -5.0), (-45.0, 5.0), (-70.0, 5.0)]),
        Obstacle.disc("ob-out", "Tower", (-100.0, 0.0), 10.0),  # 90 m
    ]
    drones = [vehicle(1), vehicle(2, 30.0, 30.0), vehicle(3, 40.0, 40.0), vehicle(4, -20.0, 0.0)]
    absent = ["tg-edge-out", "Just Outside", "tg-poly-out", "Outside Field", "ob-out", "Tower",
              "d3"]
    sc = tiny_scenario(drones, obstacles=obstacles, targets=targets)
    async with gateway_session(sc) as s:
        gw = s.gw

        def check(out: Outcome) -> None:
            assert out.status is Status.OK
            assert out.message == "d1 senses 4 targets, 2 obstacles, 2 drones within 50 m"
            data = out.data
            assert [(t["id"], t["kind"], t["distance_m"]) for t in data["targets"]] == [
                ("tg-in", "fixed", 28.0), ("tg-station", "waypoint", 42.1),
                ("tg-poly-part", "polygon", 44.7), ("tg-part", "circle", 47.0)]
            assert [(o["id"], o["distance_m"]) for o in data["obstacles"]] == [
                ("ob-in", 25.0), ("ob-poly-part", 45.0)]
            assert [(d["id"], d["kind"], d["distance_m"]) for d in data["drones"]] == [
                ("d4", "vehicle", 20.0), ("d2", "vehicle", 42.4)]
            assert data["targets"][0]["position"] == [30.0, 0.0, 0.0]
            assert data["drones"][1]["position"] == [30.0, 30.0, 0.0]
            assert set(data) == {"targets", "obstacles", "drones"}
            assert not _mentions(out, absent)
            assert_consistent(s, out, "d1")

        check(gw.nearby("d1"))
        # Altitude does not matter: the same from 20 m up.
        assert (await gw.take_off("d1", 20)).ok
        check(gw.nearby("d1"))

        # Perception follows the drone: out here there is nothing around.
        assert (await gw.move_to("d1", 150, 150, 20)).ok
        out = gw.nearby("d1")
        assert out.message == "d1 senses 0 targets, 0 obstacles, 0 drones within 50 m"
        assert out.data == {"targets": [], "obstacles": [], "drones": []}

        # ...and other drones see it where it now is: d3 at (40, 40) no longer sees d1.
        seen = [d["id"] for d in gw.nearby("d3").data["drones"]]
        assert seen == ["d2"]

        # No other primitive reports entities: the world's lists never leak.
        outcomes = [gw.drone_state("d1"), gw.send_message("d1", "d2", "x"),
                    gw.broadcast("d1", "y"), gw.read_messages("d2"),
                    await gw.take_photo("d1"), await gw.hover("d1", 1),
                    await gw.rotate("d1", 90), await gw.move_to("d1", 0, 0, 20)]
        every = [t.id for t in targets] + [t.name for t in targets] + \
            [o.id for o in obstacles] + [o.name for o in obstacles]
        for out in outcomes:
            assert out.ok, out
            assert not _mentions(out, every), out
        assert all(st.drone in {"d1", "d2", "d3", "d4"} for st in gw.list_drones())

        await expect_refusal(s, lambda: gw.nearby("zz"), "unknown drone 'zz'")
        await expect_refusal(s, lambda: gw.nearby(None), "unknown drone None")


async def test_messages_between_drones():
    sc = tiny_scenario([vehicle(1), vehicle(2, 5.0, 0.0), vehicle(3, 10.0, 0.0),
                        vehicle(4, 15.0, 0.0)])
    async with gateway_session(sc) as s:
        gw, rec = s.gw, s.swarm.recorder
        out = gw.send_message("d1", "d2", "hello d2")
        assert out.status is Status.OK and out.message == "d1 sent a message to d2"
        assert_consistent(s, out, "d1")
        sent = rec.events("d1", kinds=["message_sent"])
        assert [(e.data["to"], e.data["text"]) for e in sent] == [("d2", "hello d2")]
        assert gw.send_message("d1", "d2", "second").ok

        out = gw.read_messages("d2")
        assert out.status is Status.OK and out.message == "d2 has 2 new messages"
        assert [(m["from"], m["text"]) for m in out.data["messages"]] == [
            ("d1", "hello d2"), ("d1", "second")]
        assert all(m["t_s"] == pytest.approx(s.now_s, abs=0.1) for m in out.data["messages"])
        out = gw.read_messages("d2")
        assert out.message == "d2 has 0 new messages" and out.data == {"messages": []}

        out = gw.broadcast("d3", "all: regroup")
        assert out.status is Status.OK and out.message == "d3 broadcast to 3 drones"
        assert out.data == {"recipients": 3}
        (event,) = rec.events("d3", kinds=["message_broadcast"])
        assert event.data["recipients"] == ("d1", "d2", "d4")
        for d in ("d1", "d2", "d4"):
            got = gw.read_messages(d).data["messages"]
            assert [(m["from"], m["text"]) for m in got] == [("d3", "all: regroup")]
        assert gw.read_messages("d3").data["messages"] == []

        # Messages go between drones in the air and on the ground alike.
        assert (await gw.take_off("d4", 10)).ok
        assert gw.send_message("d4", "d1", "airborne").ok
        assert [m["text"] for m in gw.read_messages("d1").data["messages"]] == ["airborne"]

        for sender, call, reason in [
            ("d1", lambda: gw.send_message("d1", "d1", "me"), "send_message refused: drone d1 "
             "cannot message itself"),
            ("d1", lambda: gw.send_message("d1", "d9", "hi"), "send_message refused: unknown "
             "receiving drone 'd9' (known: d1, d2, d3, d4)"),
            (None, lambda: gw.send_message("d9", "d1", "hi"), "send_message refused: unknown "
             "drone 'd9'"),
            ("d1", lambda: gw.send_message("d1", ["d2"], "hi"), "unknown receiving drone ['d2']"),
            ("d1", lambda: gw.send_message("d1", None, "hi"), "unknown receiving drone None"),
            ("d1", lambda: gw.send_message("d1", "d2", "   "), "message text is empty"),
            ("d1", lambda: gw.send_message("d1", "d2", None), "message text is empty"),
            ("d1", lambda: gw.send_message("d1", "d2", "x" * (MAX_TEXT_CHARS + 1)),
             f"message text is {MAX_TEXT_CHARS + 1} characters, limit {MAX_TEXT_CHARS}"),
            ("d2", lambda: gw.broadcast("d2", ""), "broadcast refused: message text is empty"),
            (None, lambda: gw.broadcast({"d": 1}, "hi"), "broadcast refused: unknown drone"),
            (None, lambda: gw.read_messages("d9"), "read_messages refused: unknown drone 'd9'"),
        ]:
            out = await expect_refusal(s, call, reason)
            # Like every other refusal, one for a drone of the fleet comes with its state.
            assert (out.state.drone if out.state else None) == sender, out
        for d in ("d1", "d2", "d3", "d4"):  # nothing was delivered by a refused call
            assert gw.read_messages(d).data == {"messages": []}


async def test_charge_at_a_station():
    station = Target.disc("st-1", "Station One", "waypoint", (50.0, 0.0, 0.0), 5.0,
                          charge_rate_pct_s=1.0)
    drones = [vehicle(1), vehicle(2, 300.0, 0.0), vehicle(3, 25.0, 0.0)]
    async with gateway_session(tiny_scenario(drones, targets=[station])) as s:
        gw, ap = s.gw, s.ap("d1")
        await expect_refusal(s, gw.charge("d2"), "charge refused: no charging station within "
                             "50 m of d2")
        await expect_refusal(s, gw.charge("d3"), "charge refused: d3 is on the ground 20 m "
                             "from station st-1: take off and charge again")
        await expect_refusal(s, gw.charge("nobody"), "unknown drone 'nobody'")

        assert (await gw.take_off("d1", 10)).ok
        s.services.operator_reset_batteries(40.0)
        await s.settle()
        t0 = s.now_s
        out = await gw.charge("d1")
        assert out.status is Status.OK, out
        # Telemetry carries whole percent, truncated: the gateway calls a drone on its station at
        # 99 % charged (mavlink_gateway/payload.py, FULL_PCT).
        m = re.fullmatch(r"d1 charged at st-1 from (\d+)% to (99|100)%", out.message)
        assert m and 35 <= int(m.group(1)) <= 40, out.message
        assert_consistent(s, out, "d1")
        assert out.state.flight_state == "on_ground" and not out.state.armed
        await s.settle()  # one called charged at 99 % charges on to full where it rests
        # It flew there (no teleport), landed on the station, and charged in simulated time.
        assert math.hypot(ap.position_m[0] - 50.0, ap.position_m[1]) <= 5.0
        assert not ap.in_air and not ap.armed and ap.battery_pct == 100.0
        no_teleport(s, "d1", t0)
        kinds = [e.kind for e in s.swarm.recorder.events("d1", t0_s=t0)]
        assert kinds.index("landed") < kinds.index("charging") < kinds.index("charged")
        assert s.now_s - t0 >= 60.0  # at least 60 % at 1 %/s

        # Landed on the station by `land`, it charges where it stands (resting disarmed on a
        # station charges anyway, and in stepped mode charging keeps the clock running).
        assert (await gw.take_off("d1", 5)).ok
        s.services.operator_reset_batteries(50.0)
        await s.settle()
        t1 = s.now_s
        assert (await gw.land("d1")).ok
        out = await gw.charge("d1")
        assert out.status is Status.OK, out
        assert re.fullmatch(r"d1 charged at st-1 from \d+% to (99|100)%", out.message), \
            out.message
        assert_consistent(s, out, "d1")
        await s.settle()
        kinds = [e.kind for e in s.swarm.recorder.events("d1", t0_s=t1)]
        assert "takeoff" not in kinds
        assert kinds.index("landed") < kinds.index("charging") < kinds.index("charged")
        assert ap.battery_pct == 100.0 and s.now_s - t1 >= 50.0


async def test_operator_resets():
    drones = [vehicle(1), vehicle(2, 10.0, 0.0), vehicle(3, 20.0, 0.0, battery_pct=80.0)]
    async with gateway_session(tiny_scenario(drones), telemetry_hz=None) as s:  # defaults
        gw, rec = s.gw, s.swarm.recorder
        assert (await gw.take_off("d1", 10)).ok
        assert (await gw.move_to("d1", 50, 50, 10)).ok
        assert (await gw.set_home("d1")).ok
        assert (await gw.take_off("d2", 15)).ok
        assert gw.send_message("d1", "d3", "pending").ok

        t0 = s.now_s
        assert gw.operator_land_all() is None
        for d, (x, y) in [("d1", (50.0, 50.0)), ("d2", (10.0, 0.0)), ("d3", (20.0, 0.0))]:
            ap = s.ap(d)
            assert ap.position_m[2] == 0.0 and not ap.in_air and not ap.armed
            assert math.hypot(ap.position_m[0] - x, ap.position_m[1] - y) < 1.0
        assert len(rec.events(t0_s=t0, kinds=["operator_place"])) == 3
        await s.settle()
        assert [st.flight_state for st in gw.list_drones()] == ["on_ground"] * 3
        assert not any(st.armed for st in gw.list_drones())

        gw.operator_reset_batteries()
        assert [s.ap(d).battery_pct for d in ("d1", "d2", "d3")] == [100.0] * 3
        assert len(rec.events(t0_s=t0, kinds=["operator_battery"])) == 3

        gw.operator_reset_to_start()
        # The restored home reaches the gateway at once, not at the next 0.5 Hz HOME_POSITION.
        link, t_wall = s.link("d1"), asyncio.get_running_loop().time()
        while math.dist(link.home_m, (0.0, 0.0, 0.0)) > 0.2:
            assert asyncio.get_running_loop().time() - t_wall < 0.5, link.home_m
            await asyncio.sleep(0.01)
        for d in drones:
            ap = s.ap(d.id)
            assert ap.position_m == d.position_m and ap.home_m == d.home_m
            assert ap.battery_pct == d.battery_pct and not ap.armed and not ap.in_air
        assert gw.read_messages("d3").data == {"messages": []}  # inboxes emptied
        await s.settle()
        for st, d in zip(gw.list_drones(), drones, strict=True):
            assert math.dist(st.position_m, d.position_m) < 0.5
            assert st.flight_state == "on_ground"
        # The fleet flies again from the start.
        out = await gw.take_off("d1", 10)
        assert out.ok and math.hypot(*s.ap("d1").position_m[:2]) < 0.5
