"""Property test: random sequences of gateway primitives, with sensible, random and absurd
arguments, against one stepped swarm over real UDP (reset between examples by the operator).

After every call: the primitive returned an Outcome with a readable message and never raised;
a refused call changed nothing (no truth state, no truth event, no simulated time); the state
it reports agrees with the ground truth; no outcome names an entity the drone cannot sense;
the swarm comes to rest (nothing runs on after a primitive ends). After every sequence the
gateway's view of every drone agrees with the truth.
"""

from __future__ import annotations

import asyncio
import json
import math
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Any

import pytest
from hypothesis import HealthCheck, Phase, event, given, settings
from hypothesis import strategies as st

from emulator.world import Obstacle, Target
from mavlink_gateway import Gateway, Outcome, Status
from tests.gateway_fixtures import (
    GatewaySession,
    assert_consistent,
    gateway_session,
    same_truth,
    truth,
)
from tests.scenario_fixtures import tiny_scenario, vehicle

pytestmark = pytest.mark.mavsdk

IDS = ("d1", "d2", "d3")
TARGETS = [
    Target.disc("ST-Kilo", "Station Kilo", "waypoint", (40.0, 40.0, 0.0), 6.0,
                charge_rate_pct_s=5.0),
    Target.disc("TG-Lima", "Target Lima", "fixed", (-60.0, 30.0, 0.0), 3.0),
    Target.polygon("TG-Mike", "Field Mike",
                   [(150.0, 0.0), (170.0, 0.0), (170.0, 20.0), (150.0, 20.0)]),
    Target.disc("TG-Quebec", "Target Quebec", "fixed", (400.0, 400.0, 0.0), 3.0),  # never near
]
OBSTACLES = [
    Obstacle.disc("OB-Oscar", "Tower Oscar", (60.0, 0.0), 8.0),
    Obstacle.polygon("OB-Papa", "Barn Papa", [(-10.0, 80.0), (10.0, 80.0), (10.0, 100.0),
                                              (-10.0, 100.0)], height_m=12.0),
]
SCENARIO = tiny_scenario(
    [vehicle(1), vehicle(2, 10.0, 0.0), vehicle(3, 20.0, 0.0, battery_pct=60.0)],
    obstacles=OBSTACLES, targets=TARGETS)
ENTITY_WORDS = {e.id: (e.id, e.name) for e in (*TARGETS, *OBSTACLES)}

# ------------------------------------------------------------------------ strategies
# Arguments come in two flavours: sensible ones (a drone of the fleet, coordinates around it,
# altitudes it can fly) so that sequences really fly, and anything at all.
ABSURD = st.sampled_from([math.nan, math.inf, -math.inf, -1e9, 1e12, 10**400, 0, -0.0, "10",
                          None, True, [], {}, (1, 2)])


def _args(sensible: bool) -> dict[str, st.SearchStrategy]:
    if sensible:
        a = {"drone": st.sampled_from(IDS), "coord": st.floats(-100.0, 100.0),
             "alt": st.floats(3.0, 40.0), "heading": st.floats(-360.0, 720.0),
             "distance": st.floats(2.0, 60.0), "dz": st.floats(-3.0, 3.0),
             "duration": st.floats(0.5, 10.0), "text": st.text(min_size=1, max_size=20)}
    else:
        a = {"drone": st.one_of(st.sampled_from(IDS), st.sampled_from(
                 ["d9", "", "D1", None, 7, ["d1"], {"d1"}, 10**5000])),
             "coord": st.one_of(st.floats(-150.0, 150.0), ABSURD),
             "alt": st.one_of(st.floats(-10.0, 200.0), ABSURD,
                              st.sampled_from([0.5, 0.99, 1.0, 120.0, 120.01])),
             "heading": st.one_of(st.floats(allow_nan=True), ABSURD),
             "distance": st.one_of(st.floats(-10.0, 20_000.0), ABSURD),
             "dz": st.one_of(st.floats(-50.0, 200.0), ABSURD),
             "duration": st.one_of(st.floats(-5.0, 20.0), ABSURD, st.just(3601.0)),
             "text": st.one_of(st.text(max_size=30),
                               st.sampled_from(["", "   ", "x" * 501, None, 42]))}
    point = st.one_of(st.tuples(a["coord"], a["coord"]),
                      st.tuples(a["coord"], a["coord"], a["alt"]))
    a["waypoints"] = st.lists(point, min_size=1, max_size=3) if sensible else st.one_of(
        st.lists(point, min_size=1, max_size=3),
        st.sampled_from([[], None, "abc", [[1]], [[0, 0]] * 101, {"x": 1}, [b"\x00\x00"]]))
    return a


@dataclass(frozen=True)
class Call:
    name: str
    args: tuple[Any, ...]

    @property
    def drone(self) -> Any:
        return self.args[0] if self.args else None

    def __repr__(self) -> str:
        shown = ", ".join(_short(a) for a in self.args)
        return f"{self.name}({shown})"

    async def run(self, gw: Gateway) -> Outcome | list:
        result = getattr(gw, self.name)(*self.args)
        return await result if asyncio.iscoroutine(result) else result


def _short(value: Any) -> str:
    try:
        text = repr(value)
    except ValueError:
        text = f"<{type(value).__name__}>"
    return text if len(text) <= 40 else text[:37] + "..."


def _call(name: str, *args: st.SearchStrategy) -> st.SearchStrategy[Call]:
    return st.tuples(*args).map(lambda a: Call(name, a))


def _calls(sensible: bool) -> st.SearchStrategy[Call]:
    a = _args(sensible)
    d = a["drone"]
    return st.one_of(
        _call("take_off", d, a["alt"]),
        _call("land", d),
        _call("move_to", d, a["coord"], a["coord"], a["alt"]),
        _call("move_to", d, a["coord"], a["coord"], a["alt"]),
        _call("move_towards", d, a["heading"], a["distance"], a["dz"]),
        _call("change_altitude", d, a["alt"]),
        _call("hover", d, a["duration"]),
        _call("rotate", d, a["heading"]),
        _call("return_home", d),
        _call("set_home", d),
        _call("move_along_path", d, a["waypoints"]),
        _call("take_photo", d),
        _call("charge", d),
        _call("send_message", d, d, a["text"]),
        _call("broadcast", d, a["text"]),
        _call("read_messages", d),
        _call("nearby", d),
        _call("drone_state", d),
        _call("list_drones"),
    )


# Mostly sensible calls, some with anything at all; a sequence starts by taking some drones
# off, so that most calls find their drone in the air.
call = st.one_of(_calls(True), _calls(True), _calls(False))
take_off = _call("take_off", st.sampled_from(IDS), st.floats(3.0, 30.0))
sequence = st.tuples(st.lists(take_off, max_size=3, unique_by=lambda c: c.drone),
                     st.lists(call, min_size=1, max_size=8)).map(lambda p: p[0] + p[1])


# ------------------------------------------------------------------------ invariants
def _sensed_words(s: GatewaySession, drone: str) -> set[str]:
    p = s.services.sense(drone)
    return {w for e in (*p.targets, *p.obstacles) for w in ENTITY_WORDS[e.id]}


def _leaks(outcome: Outcome, allowed: set[str]) -> list[str]:
    text = json.dumps(outcome.to_dict(), default=str).lower()
    return [w for words in ENTITY_WORDS.values() for w in words
            if w not in allowed and w.lower() in text]


async def _step(s: GatewaySession, c: Call) -> None:
    await asyncio.wait_for(s.swarm.wait_idle(), 20.0)
    await s.settle(full=False)
    known = c.drone if isinstance(c.drone, str) and c.drone in IDS else None
    before = {d: truth(s, d) for d in IDS}
    events = len(s.swarm.recorder.events())
    t0 = s.now_s
    allowed = _sensed_words(s, known) if known else set()

    result = await c.run(s.gw)

    if c.name == "list_drones":
        assert [st_.drone for st_ in result] == list(IDS)
        for st_ in result:
            assert_consistent(s, Outcome(Status.OK, "listed", st_), st_.drone)
        return
    out = result
    assert isinstance(out, Outcome), (c, out)
    event(f"{c.name}: {out.status}")  # counted in Hypothesis' statistics
    assert isinstance(out.status, Status) and isinstance(out.message, str), (c, out)
    assert out.message.strip(), (c, out)
    assert out.status is not Status.TIMEOUT, (c, out)  # calm air, short moves: all end in time
    if known is None:
        assert out.status is Status.REJECTED and "unknown drone" in out.message, (c, out)
    if out.status is Status.REJECTED:
        assert s.now_s == t0, (c, out, s.now_s - t0)
        for d, was in before.items():
            assert same_truth(truth(s, d), was), (c, out, d, was, truth(s, d))
        new = s.swarm.recorder.events()[events:]
        assert not new, (c, out, new)
    if known is not None:
        assert out.state is not None and out.state.drone == known, (c, out)
        failsafe = out.status is Status.BLOCKED and "battery" in out.message.lower()
        if not failsafe:  # a failsafe leaves it flying home: nothing settled to compare
            assert_consistent(s, out, known)
        allowed |= _sensed_words(s, known)
    assert not _leaks(out, allowed), (c, out, _leaks(out, allowed))
    # Nothing runs on after a primitive ended (a landing's disarm, a charge or a failsafe
    # return may still finish, in simulated time).
    await asyncio.wait_for(s.swarm.wait_idle(), 20.0)


async def _example(s: GatewaySession, calls: list[Call]) -> None:
    s.gw.operator_reset_to_start()
    await s.settle()
    for c in calls:
        await _step(s, c)
    await s.settle()  # every drone's telemetry agrees with the truth in full
    for st_ in s.gw.list_drones():
        ap = s.ap(st_.drone)
        assert st_.armed == ap.armed and st_.mode == ap.mode.name.lower(), (st_, ap.mode)
        assert_consistent(s, Outcome(Status.OK, "listed", st_), st_.drone, tolerance_m=0.5)


def test_random_primitive_sequences_keep_every_drone_consistent():
    """One swarm and one gateway for every example (an operator reset puts the fleet back at
    its start in between), on an event loop of its own that runs each example to its end.
    Derandomized, so every run checks the same sequences; no shrinking (each step flies)."""
    loop = asyncio.new_event_loop()
    session = gateway_session(SCENARIO)
    try:
        s = loop.run_until_complete(session.__aenter__())
        try:
            run: Callable[[Awaitable[None]], None] = loop.run_until_complete

            @settings(max_examples=60, deadline=None, database=None, derandomize=True,
                      phases=[Phase.explicit, Phase.generate],
                      suppress_health_check=[HealthCheck.too_slow,
                                             HealthCheck.data_too_large])
            @given(sequence)
            def check(calls: list[Call]) -> None:
                run(_example(s, calls))

            check()
        finally:
            loop.run_until_complete(session.__aexit__(None, None, None))
    finally:
        loop.run_until_complete(loop.shutdown_default_executor())
        loop.close()
