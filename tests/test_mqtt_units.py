"""The MQTT bus's pure parts: broker URLs, topics, event classification, request parsing,
and a connection that never waits while no broker answers."""

from __future__ import annotations

import asyncio
import json

import jsonschema
import pytest

from agent_contract import AgentTools
from mqtt_bus.commands import CommandService, drone_tool_names
from mqtt_bus.connection import BusConnection
from mqtt_bus.payloads import DroneSample, osd_payload, state_payload, statustext_event
from mqtt_bus.schemas import SCHEMAS
from mqtt_bus.topics import BenchTopics, SessionTopics
from mqtt_bus.url import parse_broker_url
from tests.ports import unused_tcp_port


def test_broker_urls_parse_with_defaults_tls_and_credentials() -> None:
    url = parse_broker_url("mqtt://broker")
    assert (url.host, url.port, url.tls, url.prefix, url.username) == \
        ("broker", 1883, False, "mavswarm", None)
    url = parse_broker_url("mqtts://op%40site:p%3Ass@10.0.0.2/fleet/a?ca=/etc/ca.pem")
    assert (url.host, url.port, url.tls, url.prefix) == ("10.0.0.2", 8883, True, "fleet/a")
    assert (url.username, url.password, url.ca_file) == ("op@site", "p:ss", "/etc/ca.pem")
    assert url.redacted() == "mqtts://op@site@10.0.0.2:8883/fleet/a"
    assert "p:ss" not in url.redacted()


@pytest.mark.parametrize("text, needle", [
    ("", "empty"), ("tcp://h", "scheme must be"), ("mqtt://", "names no host"),
    ("mqtt://h:0", "port 0"), ("mqtt://h:70000", "out of range"),
    ("mqtt://h/a/#", "cannot be an MQTT topic level"), ("mqtt://h/x?ca=f", "mqtts:// only"),
    ("mqtts://h/x?tls=1", "unknown option 'tls'"),
])
def test_bad_broker_urls_name_the_problem(text: str, needle: str) -> None:
    with pytest.raises(ValueError, match=needle.replace("(", r"\(")):
        parse_broker_url(text)


def test_topics_and_their_levels() -> None:
    t = SessionTopics("mavswarm", "s1")
    assert (t.status, t.osd("d1"), t.state("d1"), t.events("d1"), t.services_reply("d1")) == (
        "mavswarm/s1/status", "mavswarm/s1/d1/osd", "mavswarm/s1/d1/state",
        "mavswarm/s1/d1/events", "mavswarm/s1/d1/services_reply")
    assert t.services_filter == "mavswarm/s1/+/services"
    assert t.drone_of_services("mavswarm/s1/d7/services") == "d7"
    assert t.drone_of_services("mavswarm/s2/d7/services") is None
    assert t.drone_of_services("mavswarm/s1/d7/x/services") is None
    b = BenchTopics("p/q", "run-1")
    assert (b.tasks, b.progress, b.status) == ("p/q/bench/run-1/tasks",
                                                "p/q/bench/run-1/progress",
                                                "p/q/bench/run-1/status")
    for bad in ("", "a/b", "+", "#", "x" * 65, "d 1"):
        with pytest.raises(ValueError, match="MQTT topic level"):
            SessionTopics("mavswarm", bad)


def test_statustexts_become_holds_failsafes_or_plain_texts() -> None:
    hold = statustext_event("d1", 1.0, 4, "Obstacle Tower A ahead: holding")
    assert (hold["kind"], hold["obstacle"]) == ("obstacle_hold", "Tower A")
    crit = statustext_event("d1", 1.0, 2, "Critical battery 14%: returning home")
    assert (crit["kind"], crit["reason"], crit["action"]) == \
        ("failsafe", "battery_critical", "returning_home")
    emer = statustext_event("d1", 1.0, 2, "Emergency battery 5%: landing")
    assert (emer["reason"], emer["action"]) == ("battery_emergency", "landing")
    lost = statustext_event("d1", 1.0, 4, "Offboard setpoints lost: holding")
    assert (lost["kind"], lost["reason"]) == ("failsafe", "offboard_lost")
    plain = statustext_event("d1", 1.0, 6, "Landing detected")
    assert plain == {"drone": "d1", "time_s": 1.0, "kind": "statustext", "severity": 6,
                     "text": "Landing detected"}
    for event in (hold, crit, emer, lost, plain):
        jsonschema.validate(event, SCHEMAS["events"])


def test_samples_become_osd_and_state_payloads_with_their_schemas() -> None:
    s = DroneSample("d1", 12.3456, (1.234, -5.0, 10.0), (47.1, 8.2, 498.0), (1.0, 2.0, 0.5),
                    359.96, 87.25, "mission", True, "flying", (0.0, 0.0, 0.0),
                    (47.0, 8.0, 488.0), "move_to")
    osd = osd_payload(s)
    assert osd["position"] == {"x_m": 1.23, "y_m": -5.0, "z_m": 10.0, "altitude_m": 10.0}
    assert osd["time_s"] == 12.346 and osd["battery_pct"] == 87.2
    state = state_payload(s)
    assert state["primitive"] == "move_to" and state["home"]["latitude_deg"] == 47.0
    jsonschema.validate(osd, SCHEMAS["osd"])
    jsonschema.validate(state, SCHEMAS["state"])


def test_mqtt_commands_are_the_drone_tools_of_the_registry() -> None:
    names = drone_tool_names()
    assert {"take_off", "move_to", "take_photo", "send_message", "wait"} <= set(names)
    assert "list_drones" not in names and "finish" not in names


async def test_a_request_that_cannot_be_parsed_reaches_no_tool() -> None:
    reached: list[str] = []

    async def tools_for(drone: str) -> AgentTools:
        reached.append(drone)
        raise AssertionError("no tool may run for a bad request")

    conn = BusConnection(parse_broker_url("mqtt://127.0.0.1:1"), client_id="t",
                         status_topic="s", online_payload=b"1", offline_payload=b"0")
    service = CommandService(SessionTopics("mavswarm", "s1"), conn, ["d1", "d2"], tools_for)
    bad = [b"\xff\xfe", b"{", b"7", b'{"id": 5, "tool": "land"}',
           b'{"id": "a b", "tool": "land"}', b'{"id": "x", "tool": "land", "args": [1]}',
           b'{"id": "x", "tool": "finish"}', b'{"id": "x", "tool": "land", "who": 1}',
           json.dumps({"id": "x", "tool": "land", "args": {"drone_id": "d2"}}).encode(),
           b"[" * 100_000]
    for payload in bad:
        reply = await service.run("d1", payload)
        assert reply["status"] == "error" and reply["message"], payload[:40]
        jsonschema.validate(reply, SCHEMAS["services_reply"])
    reply = await service.run("d3", b'{"id": "x", "tool": "land"}')
    assert "unknown drone 'd3'" in reply["message"]
    assert reached == []


async def test_link_commands_where_the_links_are_real_are_refused() -> None:
    async def tools_for(drone: str) -> AgentTools:
        raise AssertionError("link commands reach no agent tool")

    conn = BusConnection(parse_broker_url("mqtt://127.0.0.1:1"), client_id="t",
                         status_topic="s", online_payload=b"1", offline_payload=b"0")
    bridged = CommandService(SessionTopics("mavswarm", "fleet"), conn, ["d1"], tools_for)
    for tool in ("get_link", "set_link"):
        reply = await bridged.run("d1", json.dumps({"id": "x", "tool": tool}).encode())
        assert reply["status"] == "rejected" and "real radio links" in reply["message"]
        jsonschema.validate(reply, SCHEMAS["services_reply"])
    unknown = await bridged.run("d1", b'{"id": "x", "tool": "set_links"}')
    assert unknown["status"] == "error" and "get_link, set_link" in unknown["message"]


async def test_publishing_never_waits_while_no_broker_answers() -> None:
    port = unused_tcp_port()  # nobody listens here
    conn = BusConnection(parse_broker_url(f"mqtt://127.0.0.1:{port}"), client_id="t",
                         status_topic="x/status", online_payload=b"1", offline_payload=b"0",
                         queue_size=5, backoff_s=(0.05, 0.2))
    async with conn:
        await asyncio.sleep(0.3)  # a few failed connection attempts
        assert not conn.stats.connected and conn.stats.last_error
        assert all(not conn.publish("x/osd", b"{}") for _ in range(100))
        assert conn.stats.dropped_offline == 100
        accepted = [conn.publish("x/events", b"{}", qos=1) for _ in range(8)]
        assert accepted == [True] * 5 + [False] * 3  # QoS 1 waits on the bounded queue
        assert conn.stats.dropped_full == 3 and conn.queued == 5
        assert conn.publish("x/state", b"{}", qos=1, retain=True)  # kept for reconnects
        assert conn.queued == 5
    assert conn.stats.connects == 0 and conn.stats.published == 0
