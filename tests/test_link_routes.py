"""Link faults changed at run time by an operator, over `mavswarm serve`'s REST API (uvicorn on a
free port, real HTTP) and the MQTT services topics (a real Mosquitto with the shipped ACL):
an outage really cuts a drone's telemetry off from the gateway, bad settings change nothing,
agents can neither read nor set links, and nothing changes while a benchmark task runs."""

from __future__ import annotations

import asyncio
import contextlib
import functools
import time
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import httpx
import jsonschema
import pytest

from benchmark.server import Hub, Role, create_app
from benchmark.server.hub import LiveSession
from benchmark.server.serve import live_hub, mqtt_refusal, serve_asgi
from console.cli import console_for_hub, swarm_console
from mqtt_bus.schemas import SCHEMAS
from mqtt_bus.swarm_bus import gateway_session_bus, swarm_session_bus
from mqtt_bus.url import parse_broker_url
from tests.bench_fixtures import small_session, write_json
from tests.conftest import SwarmFactory
from tests.mosquitto_broker import Broker
from tests.mqtt_helpers import broker, listener, request

pytestmark = [pytest.mark.mavsdk]
__all__ = ["broker"]  # the fixture, used by name

AGENT, OPERATOR, ADMIN = ({"X-API-Key": k} for k in ("k-agent", "k-operator", "k-admin"))
CLEAN = {"loss": 0.0, "latency_ms": 0.0, "jitter_ms": 0.0, "duplicate": 0.0, "reorder": 0.0,
         "outages": []}


@contextlib.asynccontextmanager
async def _serving(tmp_path: Path, data: dict[str, Any], b: Broker
                   ) -> AsyncIterator[tuple[httpx.AsyncClient, LiveSession]]:
    """`mavswarm serve --mqtt` of one session with its console, as serve_rest assembles it,
    on a free port."""
    path = write_json(tmp_path / f"{data['id']}.json", data)
    url = parse_broker_url(b.url())
    async with live_hub([path]) as hub:
        (live,) = hub.sessions.values()
        _keys(hub, live.id)
        ready: asyncio.Future[str] = asyncio.get_running_loop().create_future()
        app = create_app(hub)
        console_for_hub(app, hub, [])
        server = asyncio.create_task(serve_asgi(app, host="127.0.0.1", port=0,
                                                on_ready=ready.set_result))
        try:
            async with gateway_session_bus(
                    url, live.id, live.swarm, live.gateway, services=live.services,
                    refusal=functools.partial(mqtt_refusal, hub, live.id)) as bus, \
                    httpx.AsyncClient(base_url=await asyncio.wait_for(ready, 30.0),
                                      timeout=30.0) as client:
                assert await bus.connection.wait_connected(30.0)  # subscribed to services
                yield client, live
        finally:
            server.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await server


def _keys(hub: Hub, session_id: str) -> None:
    hub.add_key("k-agent", Role.AGENT, session_id)
    hub.add_key("k-operator", Role.OPERATOR)
    hub.add_key("k-admin", Role.ADMIN)


async def _until(condition: Any, what: str, timeout_s: float = 45.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not await condition():
        assert time.monotonic() < deadline, f"not within {timeout_s} s: {what}"
        await asyncio.sleep(0.2)


BAD_BODIES = [
    ({"loss": 1.5}, "loss must be a number within [0, 1], got 1.5"),
    ({"latency_ms": -5}, "latency_ms must be a number of milliseconds within [0, 10000]"),
    ({"latency_ms": 1e300}, "numbers are limited to +/-1e+09"),
    ({"duplicate": "0.2"}, "duplicate must be a number within [0, 1], got '0.2'"),
    ({"reorder": True}, "reorder must be a number within [0, 1], got True"),
    ({"loss": 0.1, "bogus": 1}, "bogus is not a link setting"),
    ({"downlink": {"outages": [[50, 10]]}}, "outages[0] must be [start_s, end_s]"),
    ({"downlink": {"outages": [[k, k + 0.5] for k in range(65)]}}, "at most 64 per direction"),
    ({"uplink": 3}, "uplink must be an object"),
    ([0.5], "must be an object"),
]


async def test_operators_change_links_over_rest_and_mqtt_and_an_outage_silences_a_drone(
        tmp_path: Path, broker: Broker) -> None:
    data = {**small_session(["takeoff_hold"]), "id": "free", "tasks": []}
    async with _serving(tmp_path, data, broker) as (client, live), \
            listener(broker, "operator", "mavswarm/free/+/services_reply") as op, \
            listener(broker, "agent", "mavswarm/free/#") as agent:
        first, second = live.services.drone_ids[:2]
        base = f"/sessions/{live.id}"
        # agents get no link route at all, reading or writing
        for method, route in (("GET", "/link-faults"), ("PUT", "/link-faults"),
                              ("GET", f"/vehicles/{first}/link"),
                              ("PUT", f"/vehicles/{first}/link")):
            answer = await client.request(method, base + route, headers=AGENT,
                                          json={"loss": 1.0})
            assert answer.status_code == 403, (route, answer.text)
            assert "may not use this route" in answer.json()["detail"]
        got = await client.get(f"{base}/link-faults", headers=OPERATOR)
        assert got.status_code == 200, got.text
        before = got.json()["link_faults"]
        assert before == {"seed": 0, "uplink": CLEAN, "downlink": CLEAN, "vehicles": {}}
        events_before = len(live.swarm.recorder.events())

        # bad bodies: a 422 naming the field, on both routes, and nothing changes
        for body, message in BAD_BODIES:
            for route in ("/link-faults", f"/vehicles/{first}/link"):
                answer = await client.put(base + route, headers=OPERATOR, json=body)
                assert answer.status_code == 422, (body, answer.text)
                assert message in answer.json()["detail"], (body, answer.json())
        for raw in (b"", b"{not json", b'{"loss": 1e999}'):
            answer = await client.put(f"{base}/link-faults", headers=OPERATOR, content=raw)
            assert answer.status_code == 422, (raw, answer.text)
        missing = await client.put(f"{base}/vehicles/d99/link", headers=OPERATOR,
                                   json={"loss": 0.1})
        assert missing.status_code == 404 and "unknown drone" in missing.json()["detail"]
        assert (await client.get(f"{base}/link-faults", headers=ADMIN)).json()[
            "link_faults"] == before
        assert len(live.swarm.recorder.events()) == events_before

        # an outage of the first drone's downlink from now on: the gateway stops hearing it
        now_s = live.services.clock_s()
        cut = await client.put(f"{base}/vehicles/{first}/link", headers=OPERATOR,
                               json={"downlink": {"outages": [[now_s, now_s + 1e6]]}})
        assert cut.status_code == 200, cut.text
        assert cut.json()["downlink"]["outages"] == [[now_s, now_s + 1e6]]
        assert cut.json()["uplink"] == CLEAN
        recorded = [e for e in live.swarm.recorder.events(first) if e.kind == "link_faults"]
        assert recorded and [list(w) for w in recorded[-1].data["downlink"]["outages"]] == [
            [now_s, now_s + 1e6]]
        links = live.gateway.drones

        async def silenced() -> bool:
            state = (await client.get(f"{base}/drones/{first}", headers=OPERATOR)).json()
            return state["state"]["flight_state"] == "unreachable" \
                and links[second].silent_for_s() < 2.0

        await _until(silenced, f"{first} reported unreachable while {second} reports")
        second_state = (await client.get(f"{base}/drones/{second}", headers=OPERATOR)).json()
        assert second_state["state"]["flight_state"] != "unreachable"

        # over MQTT: the operator clears it (the drone is heard again) and sets another
        bad = await request(op, "mavswarm/free", first, "set_link", loss=1.5)
        assert bad["status"] == "error" and "loss must be a number within [0, 1]" in \
            bad["message"]
        assert (await request(op, "mavswarm/free", first, "get_link"))["link"]["downlink"][
            "outages"] == [[now_s, now_s + 1e6]]
        cleared = await request(op, "mavswarm/free", first, "set_link")
        assert cleared["status"] == "ok" and cleared["link"] == {"uplink": CLEAN,
                                                                 "downlink": CLEAN}

        async def heard() -> bool:
            return links[first].silent_for_s() < 1.0

        await _until(heard, f"{first} heard again")
        slowed = await request(op, "mavswarm/free", second, "set_link",
                               uplink={"latency_ms": 40, "jitter_ms": 10})
        assert slowed["status"] == "ok", slowed
        view = (await client.get(f"{base}/vehicles/{second}/link", headers=OPERATOR)).json()
        assert view["uplink"]["latency_ms"] == 40.0 and view["downlink"] == CLEAN

        # an agent account cannot publish a command: the broker drops it, nothing changes
        await agent.client.publish(f"mavswarm/free/{second}/services",
                                   '{"id": "a1", "tool": "set_link", "args": {"loss": 1}}',
                                   qos=1)
        probe = await request(op, "mavswarm/free", second, "get_link")
        assert probe["link"]["uplink"]["loss"] == 0.0
        assert not [g for g in op.got if g.payload.get("id") == "a1"]
        assert not agent.of("services_reply")
        for reply in op.of("services_reply"):
            jsonschema.validate(reply.payload, SCHEMAS["services_reply"])

        # the whole set replaced over REST
        whole = await client.put(f"{base}/link-faults", headers=ADMIN,
                                 json={"seed": 3, "loss": 0.25})
        assert whole.status_code == 200, whole.text
        assert whole.json()["link_faults"]["vehicles"] == {}
        assert live.swarm.faults.gate.profile(1, 1).loss == 0.25


async def test_links_stay_put_while_a_task_runs_and_hidden_faults_stay_hidden(
        tmp_path: Path, broker: Broker) -> None:
    data = {**small_session(["takeoff_hold"]), "id": "tasked"}
    data["tasks"][0]["faults"] = {"link": {"loss": 0.2}}
    data["link_faults"] = {"seed": 9, "downlink": {"latency_ms": 5}}
    async with _serving(tmp_path, data, broker) as (client, live), \
            listener(broker, "operator", "mavswarm/tasked/+/services_reply") as op:
        drone = live.services.drone_ids[0]
        base = f"/sessions/{live.id}"
        for route in ("/link-faults", f"/vehicles/{drone}/link"):
            refused = await client.put(base + route, headers=ADMIN, json={"loss": 0.5})
            assert refused.status_code == 409, refused.text
            assert "benchmark task t01" in refused.json()["detail"]
            hidden = await client.get(base + route, headers=OPERATOR)
            assert hidden.status_code == 403 and "hidden part" in hidden.json()["detail"]
            assert (await client.get(base + route, headers=AGENT)).status_code == 403
            shown = await client.get(base + route, headers=ADMIN)
            assert shown.status_code == 200  # the task's link faults in force, as in bench run
            links = shown.json().get("link_faults", shown.json())
            assert links["uplink"]["loss"] == 0.2 and links["downlink"]["latency_ms"] == 0.0
        # the API description: the link routes for staff only
        described = {role: (await client.get("/openapi.json", headers=key)).json()["paths"]
                     for role, key in (("agent", AGENT), ("operator", OPERATOR))}
        assert not [p for p in described["agent"] if "link" in p]
        assert {"/sessions/{session_id}/link-faults",
                "/sessions/{session_id}/vehicles/{drone_id}/link"} <= set(described["operator"])
        # the console under serve: the same rules
        console = f"/console/api/live/{live.id}"
        assert (await client.get(f"{console}/link-faults", headers=AGENT)).status_code == 403
        hidden = await client.get(f"{console}/link-faults", headers=OPERATOR)
        assert hidden.status_code == 403 and "hidden part" in hidden.json()["detail"]
        refused = await client.put(f"{console}/vehicles/{drone}/link", headers=ADMIN,
                                   json={"loss": 0.5})
        assert refused.status_code == 409 and "benchmark task t01" in refused.json()["detail"]
        over_mqtt = await request(op, "mavswarm/tasked", drone, "set_link", loss=0.5)
        assert over_mqtt["status"] == "rejected"
        assert "benchmark task t01" in over_mqtt["message"]
        assert live.swarm.faults.gate.faults.to_json() == {
            "seed": 0, "uplink": {**CLEAN, "loss": 0.2}, "downlink": {**CLEAN, "loss": 0.2},
            "vehicles": {}}  # the task's; the session file's come back when it ends


async def test_the_console_of_mavswarm_up_changes_links(swarm_factory: SwarmFactory) -> None:
    swarm = await swarm_factory(2)
    ready: asyncio.Future[tuple[str, str]] = asyncio.get_running_loop().create_future()
    async with swarm_console(swarm, port=0, key="console-key",
                             on_ready=lambda url, key: ready.set_result((url, key))):
        url, key = await asyncio.wait_for(ready, 30.0)
        async with httpx.AsyncClient(base_url=f"{url}/api/live/swarm", timeout=30.0,
                                     headers={"X-API-Key": key}) as client:
            wrong = await client.put("/vehicles/d1/link", json={"loss": 1.0},
                                     headers={"X-API-Key": "nope"})
            assert wrong.status_code == 401
            bad = await client.put("/vehicles/d1/link", json={"downlink": {"loss": -1}})
            assert bad.status_code == 422 and "link.vehicles.d1.downlink.loss" in \
                bad.json()["detail"]
            assert swarm.faults.gate.faults.clean
            cut = await client.put("/vehicles/d1/link", json={"downlink": {"loss": 1.0}})
            assert cut.status_code == 200, cut.text
            assert cut.json()["downlink"]["loss"] == 1.0 and cut.json()["uplink"] == CLEAN
            stats = swarm.faults.gate.stats

            async def dropping() -> bool:
                return stats.dropped > 0

            await _until(dropping, "d1's telemetry frames dropped")  # sent at wall rates
            whole = (await client.get("/link-faults")).json()["link_faults"]
            assert set(whole["vehicles"]) == {"d1"} and whole["downlink"] == CLEAN


async def test_mavswarm_up_over_mqtt_sets_a_drones_link(broker: Broker,
                                                        swarm_factory: SwarmFactory) -> None:
    swarm = await swarm_factory(2)
    async with swarm_session_bus(parse_broker_url(broker.url()), "up", swarm) as bus, \
            listener(broker, "operator", "mavswarm/up/+/services_reply") as op:
        assert await bus.connection.wait_connected(30.0)  # subscribed to services
        bad = await request(op, "mavswarm/up", "d2", "set_link", uplink={"reorder": 2})
        assert bad["status"] == "error" and "uplink.reorder must be" in bad["message"]
        bad = await request(op, "mavswarm/up", "d2", "get_link", loss=0.5)
        assert bad["status"] == "error" and "get_link takes no args" in bad["message"]
        assert swarm.faults.gate.faults.clean
        done = await request(op, "mavswarm/up", "d2", "set_link", loss=0.3,
                             uplink={"duplicate": 0.1})
        assert done["status"] == "ok", done
        assert done["link"]["uplink"] == {**CLEAN, "loss": 0.3, "duplicate": 0.1}
        assert done["link"]["downlink"] == {**CLEAN, "loss": 0.3}
        assert swarm.faults.gate.profile(1, 0).loss == 0.3
        assert swarm.faults.gate.profile(0, 0).clean
