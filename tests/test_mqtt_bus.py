"""The MQTT bus on a real Mosquitto (started per test with the shipped ACL): telemetry and
events match the ground truth, commands fly drones and bad ones change nothing, only
operators can command, a broker restart mid-flight leaves the swarm flying and the topics
restored."""

from __future__ import annotations

import asyncio
import json
import math
import signal
import time

import aiomqtt
import jsonschema
import pytest

from mqtt_bus.schemas import SCHEMAS
from mqtt_bus.swarm_bus import swarm_session_bus
from mqtt_bus.url import parse_broker_url
from tests.conftest import SwarmFactory
from tests.mosquitto_broker import Broker
from tests.mqtt_helpers import broker, listener, request

pytestmark = [pytest.mark.mavsdk]
__all__ = ["broker"]  # the fixture, used by name

BASE = "mavswarm/s1"


def _validate(got_kind: str, payload: dict) -> None:
    jsonschema.validate(payload, SCHEMAS[got_kind])


async def test_telemetry_events_and_commands_match_the_ground_truth(
        broker: Broker, swarm_factory: SwarmFactory) -> None:
    swarm = await swarm_factory(3)
    truth = swarm.recorder
    url = parse_broker_url(broker.url())
    async with listener(broker, "agent", f"{BASE}/#") as agent, \
            listener(broker, "operator", f"{BASE}/#") as op, \
            swarm_session_bus(url, "s1", swarm, osd_hz=10) as bus:
        status = await op.wait_for(lambda g: g.kind == "status")
        assert status.payload == {"status": "online", "session": "s1",
                                  "drones": ["d1", "d2", "d3"], "commands": True}
        took = await request(op, BASE, "d1", "take_off", altitude_m=10.0)
        assert took["status"] == "ok" and took["message"] == "d1 took off to 10.0 m"
        # Through the ellipse obstacle o3 at (-90, 40): collision prevention holds d1.
        moved = await request(op, BASE, "d1", "move_to", x=-180.0, y=80.0, z=10.0)
        assert moved["status"] == "blocked", moved
        hold = await op.wait_for(lambda g: g.kind == "events"
                                 and g.payload["kind"] == "obstacle_hold")
        assert hold.payload["obstacle"] == "Ellipse Obstacle 3"
        assert (await request(op, BASE, "d1", "take_photo"))["status"] == "ok"
        photo = await op.wait_for(lambda g: g.kind == "events" and g.payload["kind"] == "photo")
        sent = await request(op, BASE, "d1", "send_message", to_drone_id="d2", text="hello d2")
        assert sent["status"] == "ok", sent
        radio = await op.wait_for(lambda g: g.kind == "events" and g.payload["kind"] == "radio")
        # a failsafe: a battery that drops to 4 % in the air lands d1 where it is (set
        # directly, as a failing cell would: an operator reset would not strike)
        swarm.fleet.bat.pct[0] = 4.0
        failsafe = await op.wait_for(lambda g: g.kind == "events"
                                     and g.payload["kind"] == "failsafe")
        assert (failsafe.payload["reason"], failsafe.payload["action"]) == \
            ("battery_emergency", "landing")
        await op.wait_for(lambda g: g.kind == "events" and g.payload.get("text")
                          == "Landing detected")
        await op.wait_for(lambda g: g.kind == "state" and g.payload["drone"] == "d1"
                          and g.payload["flight_state"] == "on_ground"
                          and g.payload["armed"] is False, timeout_s=30)
        await asyncio.sleep(0.3)
        report = bus.report()
    assert "0 dropped" in report or bus.connection.stats.dropped_full == 0

    # osd: what the drone reports, which here is the ground truth at that instant
    osd = op.of("osd", "d1")
    assert len(osd) > 20
    origin = swarm.fleet.world.origin
    for got in osd:
        p = got.payload
        x, y, z = truth.position_at("d1", p["time_s"])
        assert math.dist((p["position"]["x_m"], p["position"]["y_m"], p["position"]["z_m"]),
                         (x, y, z)) < 0.02, (p, (x, y, z))
        lat, lon, alt = origin.to_geodetic(x, y, z)
        assert abs(p["wgs84"]["latitude_deg"] - lat) < 1e-6
        assert abs(p["wgs84"]["longitude_deg"] - lon) < 1e-6
        assert abs(p["wgs84"]["altitude_amsl_m"] - alt) < 0.02
    assert max(g.payload["position"]["altitude_m"] for g in osd) > 9.0
    times = [g.payload["time_s"] for g in osd]
    assert times == sorted(times)
    # events: as the truth recorded them
    (truth_photo,) = truth.events("d1", kinds="photo")
    assert photo.payload["targets"] == sorted(truth_photo.data["targets"])
    assert photo.payload["index"] == truth_photo.data["index"]
    assert radio.payload == {"drone": "d1", "time_s": radio.payload["time_s"],
                             "kind": "radio", "to": "d2", "broadcast": False,
                             "text": "hello d2"}
    (stop,) = truth.events("d1", kinds="obstacle_stop")
    (truth_failsafe,) = truth.events("d1", kinds="failsafe")
    assert truth_failsafe.data["reason"] == failsafe.payload["reason"]
    assert stop.data["obstacle"] == "o3"
    # every payload has its schema; the agent saw telemetry but no command or reply
    for got in op.got:
        _validate(got.kind, got.payload)
    assert {g.kind for g in agent.got} == {"status", "osd", "state", "events"}
    assert len(agent.of("osd", "d1")) > 0
    # state changes carried the running primitive
    assert any(g.payload["primitive"] == "move_to" for g in op.of("state", "d1"))


async def test_bad_requests_get_clear_errors_and_change_nothing(
        broker: Broker, swarm_factory: SwarmFactory) -> None:
    swarm = await swarm_factory(2)
    url = parse_broker_url(broker.url())
    async with listener(broker, "operator", f"{BASE}/+/services_reply") as op, \
            swarm_session_bus(url, "s1", swarm, osd_hz=2) as bus:
        assert await bus.connection.wait_connected(10.0)
        before = swarm.fleet.dyn.position_m.copy()
        client = op.client

        async def raw(drone: str, payload: bytes) -> dict:
            n = len(op.got)
            await client.publish(f"{BASE}/{drone}/services", payload, qos=1)
            return (await op.wait_for(lambda g: g.kind == "services_reply", after=n)).payload

        reply = await raw("d1", b"{not json")
        assert reply["status"] == "error" and "JSON" in reply["message"]
        reply = await raw("d1", b"[1, 2]")
        assert reply["status"] == "error" and "JSON object" in reply["message"]
        reply = await raw("d1", json.dumps({"tool": "land"}).encode())
        assert reply["status"] == "error" and "\"id\"" in reply["message"]
        reply = await raw("d9", json.dumps({"id": "a", "tool": "land"}).encode())
        assert reply == {"id": "a", "drone": "d9", "tool": "land", "status": "error",
                         "message": "unknown drone 'd9' in the topic (known: d1, d2)"}
        reply = await raw("d1", json.dumps({"id": "b", "tool": "self_destruct"}).encode())
        assert reply["status"] == "error" and "unknown tool 'self_destruct'" in reply["message"]
        assert "take_off" in reply["message"] and "list_drones" not in reply["message"]
        reply = await raw("d1", json.dumps({"id": "c", "tool": "take_off",
                                            "args": {"altitude_m": "high"}}).encode())
        assert reply["status"] == "error" and "altitude_m" in reply["message"]
        reply = await raw("d1", json.dumps({"id": "d", "tool": "take_off",
                                            "args": {"drone_id": "d2",
                                                     "altitude_m": 5}}).encode())
        assert reply["status"] == "error" and "differs from the topic" in reply["message"]
        reply = await raw("d1", json.dumps({"id": "e", "tool": "land", "extra": 1}).encode())
        assert reply["status"] == "error" and "'extra'" in reply["message"]
        reply = await raw("d1", json.dumps({"id": "f", "tool": "land"}).encode())
        assert reply["status"] == "rejected"  # the gateway's refusal: on the ground
        assert "on the ground" in reply["message"]
        await asyncio.sleep(0.3)
        assert (swarm.fleet.dyn.position_m == before).all()
        assert not swarm.fleet.armed.any()


async def test_only_operators_can_command(broker: Broker, swarm_factory: SwarmFactory) -> None:
    swarm = await swarm_factory(1)
    url = parse_broker_url(broker.url())
    with pytest.raises(aiomqtt.MqttError):
        async with listener(broker, None):
            pass
    async with swarm_session_bus(url, "s1", swarm, osd_hz=2) as bus, \
            listener(broker, "operator", f"{BASE}/+/services_reply") as op, \
            listener(broker, "agent", f"{BASE}/#") as agent:
        assert await bus.connection.wait_connected(10.0)
        request_body = json.dumps({"id": "agent-1", "tool": "take_off",
                                   "args": {"altitude_m": 5}})
        await agent.client.publish(f"{BASE}/d1/services", request_body, qos=1)
        await asyncio.sleep(2.0)
        assert bus.commands is not None and bus.commands.handled == 0
        assert not op.of("services_reply") and not agent.of("services_reply")
        assert not swarm.fleet.armed.any()
        # the same request from an operator flies
        assert (await request(op, BASE, "d1", "take_off", altitude_m=5.0))["status"] == "ok"
        assert swarm.fleet.airborne[0]


async def test_a_broker_killed_mid_flight_leaves_the_swarm_flying_and_topics_restored(
        broker: Broker, swarm_factory: SwarmFactory) -> None:
    swarm = await swarm_factory(2, speed=5.0)
    url = parse_broker_url(broker.url())
    async with swarm_session_bus(url, "s1", swarm, osd_hz=10) as bus:
        assert await bus.connection.wait_connected(10.0)
        async with listener(broker, "operator", f"{BASE}/+/services_reply") as op:
            assert (await request(op, BASE, "d1", "take_off", altitude_m=10.0))["status"] \
                == "ok"
            # a long flight, left running while the broker goes away
            asyncio.get_running_loop().create_task(
                request(op, BASE, "d1", "move_to", x=0.0, y=300.0, z=10.0, timeout_s=5))
            await asyncio.sleep(0.5)
        sim_before, wall_before = swarm.fleet.now_s, time.monotonic()
        y_before = swarm.fleet.dyn.position_m[0][1]
        broker.kill()
        await asyncio.sleep(2.0)
        assert bus.connection.stats.connected is False
        rtf = (swarm.fleet.now_s - sim_before) / (time.monotonic() - wall_before) / 5.0
        assert rtf > 0.5  # the swarm kept its clock with no broker (a blocked loop: 0)
        assert swarm.fleet.dyn.position_m[0][1] > y_before + 5.0  # and d1 kept flying
        broker.start()
        assert await bus.connection.wait_connected(20.0)
        async with listener(broker, "agent", f"{BASE}/#") as agent:
            await agent.wait_for(lambda g: g.kind == "status" and g.retain
                                 and g.payload["status"] == "online")
            for drone in ("d1", "d2"):  # the retained state is back on the new broker
                await agent.wait_for(lambda g, d=drone: g.kind == "state" and g.retain
                                     and g.payload["drone"] == d)
            fresh = await agent.wait_for(lambda g: g.kind == "osd"
                                         and g.payload["drone"] == "d1")
            assert fresh.payload["position"]["y_m"] > y_before
        stats = bus.connection.stats
        assert stats.connects == 2 and stats.dropped_offline > 0
        assert "1 reconnects" in bus.report()


async def test_a_stalled_broker_does_not_slow_the_swarm(broker: Broker,
                                                        swarm_factory: SwarmFactory) -> None:
    swarm = await swarm_factory(3, speed=5.0)
    url = parse_broker_url(broker.url())
    assert broker.proc is not None
    async with swarm_session_bus(url, "s1", swarm, osd_hz=50, queue_size=200) as bus:
        assert await bus.connection.wait_connected(10.0)
        await asyncio.sleep(0.5)
        broker.proc.send_signal(signal.SIGSTOP)  # alive, connected, answering nothing
        try:
            sim_before, wall_before = swarm.fleet.now_s, time.monotonic()
            await asyncio.sleep(3.0)
            rtf = (swarm.fleet.now_s - sim_before) / (time.monotonic() - wall_before) / 5.0
            ticks = bus.telemetry.ticks
        finally:
            broker.proc.send_signal(signal.SIGCONT)
        assert rtf > 0.5  # the clock kept pace with nobody reading the bus (blocked: 0)
        assert ticks > 20  # and the bus kept sampling (50 Hz)
        async with listener(broker, "agent", f"{BASE}/+/osd") as agent:
            await agent.wait_for(lambda g: g.payload["time_s"] > sim_before + 5.0)
