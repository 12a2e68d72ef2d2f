"""Hold, and fly-to / land that replace the current goal, over real MAVLink (MAVSDK on UDP).

A pilot's Stop/Hold interrupts whatever the drone is doing: the primitive waiting on that goal
ends promptly with Status.INTERRUPTED (never a hang, never a success), and the drone hovers
where it was (HOLD) by the ground truth. `replace=True` on move_to and land does the same and
then flies the new goal, where the default still refuses a busy drone.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import time
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import TypeVar

import pytest

from emulator.clock import ClockConfig
from emulator.flight.modes import FlightMode
from emulator.link_faults import LinkFaults, LinkProfile
from emulator.services import SwarmServices
from emulator.swarm import PortPlan, Swarm
from mavlink_gateway import FleetConnection, Gateway, Outcome, Status, profiles_from_scenario
from mavlink_gateway.pacing import Thinker, run_as
from tests.gateway_fixtures import GatewaySession, gateway_session, truth
from tests.ports import unused_udp_port
from tests.scenario_fixtures import tiny_scenario, vehicle

pytestmark = pytest.mark.mavsdk

T = TypeVar("T")
PROMPT_WALL_S = 3.0  # an interrupted primitive answers within this much wall time
LOSSY = LinkProfile(loss=0.2)


async def _until(condition: Callable[[], bool], what: str, timeout_s: float = 20.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, f"never: {what}"
        await asyncio.sleep(0.005)


async def _hold_during(s: GatewaySession, call: Awaitable[Outcome], after_s: float,
                       hold: Callable[[], Awaitable[Outcome]] | None = None, *,
                       prompt_s: float = PROMPT_WALL_S) -> tuple[Outcome, Outcome]:
    """Start `call`, and once `after_s` of simulated time have passed (a stepped clock runs
    flat out: it is held there), hold the drone (or call `hold`); (the running primitive's
    outcome, the hold's). The running one must end promptly once asked to."""
    stop_s = s.now_s + after_s
    with s.services.clock_limit(stop_s):
        running = asyncio.ensure_future(call)
        await _until(lambda: s.now_s >= stop_s - 1e-6, f"{after_s} s of simulated time")
        t0 = time.monotonic()
        held = asyncio.ensure_future(hold() if hold is not None else s.gw.hold("d1"))
        out = await asyncio.wait_for(running, prompt_s)
        assert time.monotonic() - t0 < prompt_s
    return out, await held  # a goal that replaced it flies once the clock runs on


def _interrupted(out: Outcome, name: str, by: str = "hold") -> None:
    assert out.status is Status.INTERRUPTED, out
    assert out.message.startswith(f"{name} interrupted by {by}"), out.message
    assert out.state is not None and out.state.drone == "d1"


async def _stays(s: GatewaySession, drone: str, mode: FlightMode = FlightMode.HOLD) -> None:
    """The drone is airborne in `mode` and stays where it stopped (braking done)."""
    ap = s.ap(drone)
    await s.services.advance(5.0)
    first = ap.position_m
    await s.services.advance(5.0)
    assert ap.in_air and ap.mode is mode, (ap.in_air, ap.mode)
    assert math.dist(first, ap.position_m) < 0.1, (first, ap.position_m)


async def test_hold_on_the_ground_does_nothing_and_the_default_still_refuses_a_busy_drone():
    async with gateway_session(tiny_scenario([vehicle(1)])) as s:
        before = truth(s, "d1")
        out = await s.gw.hold("d1")
        assert out.status is Status.OK and out.message == "d1 is on the ground: nothing to hold"
        assert out.data == {"interrupted": None}
        assert truth(s, "d1") == before
        bad = await s.gw.hold("d9")
        assert bad.status is Status.REJECTED and "unknown drone 'd9'" in bad.message

        assert (await s.gw.take_off("d1", 10.0)).ok
        refusals: list[Outcome] = []

        async def refused_then_hold() -> Outcome:
            # the default: a busy drone refuses a second goal
            refusals.append(await s.gw.land("d1"))
            return await s.gw.hold("d1")

        out, hold = await _hold_during(s, s.gw.move_to("d1", 900.0, 0.0, 10.0), 10.0,
                                       refused_then_hold)
        assert refusals[0].status is Status.REJECTED, refusals
        assert refusals[0].message == "drone d1 is busy with move_to: wait for it to end"
        _interrupted(out, "move_to")
        assert hold.ok and hold.data == {"interrupted": "move_to"}
        assert hold.message.startswith("d1 holds at (") and "move_to interrupted" in hold.message
        assert s.link("d1").mode == "HOLD"
        await _stays(s, "d1")
        assert s.ap("d1").position_m[0] < 800.0


@pytest.mark.parametrize("name", ["take_off", "land", "return_home", "move_along_path",
                                  "hover"])
async def test_hold_interrupts_every_kind_of_goal(name: str):
    async with gateway_session(tiny_scenario([vehicle(1)])) as s:
        gw, ap = s.gw, s.ap("d1")
        if name != "take_off":
            assert (await gw.take_off("d1", 40.0)).ok
            assert (await gw.move_to("d1", 60.0, 0.0, 40.0)).ok
        call: Awaitable[Outcome] = {
            "take_off": lambda: gw.take_off("d1", 100.0),
            "land": lambda: gw.land("d1"),
            "return_home": lambda: gw.return_home("d1"),
            "move_along_path": lambda: gw.move_along_path("d1", [[60, 400], [400, 400]]),
            "hover": lambda: gw.hover("d1", 600.0),
        }[name]()
        out, hold = await _hold_during(s, call, 6.0)
        _interrupted(out, name)
        assert hold.ok and hold.data == {"interrupted": name}
        await _stays(s, "d1")
        # Not where the goal would have ended: it was interrupted on the way.
        x, y, z = ap.position_m
        assert {"take_off": z < 95.0, "land": z > 5.0, "return_home": x > 5.0,
                "move_along_path": y < 390.0, "hover": True}[name], ap.position_m
        # The drone answers the next primitive as usual.
        assert (await gw.land("d1")).ok and not ap.in_air


async def test_fly_to_and_land_replace_the_current_goal():
    async with gateway_session(tiny_scenario([vehicle(1)])) as s:
        gw, ap = s.gw, s.ap("d1")
        assert (await gw.take_off("d1", 20.0)).ok
        first, second = await _hold_during(
            s, gw.move_to("d1", 800.0, 0.0, 20.0), 5.0,
            lambda: gw.move_to("d1", 0.0, 60.0, 15.0, replace=True))
        _interrupted(first, "move_to", "move_to")
        assert second.ok and second.message == "d1 reached (0.0, 60.0, 15.0)", second
        assert math.dist(ap.position_m, (0.0, 60.0, 15.0)) < 1.0

        third, landed = await _hold_during(s, gw.move_to("d1", 0.0, 900.0, 15.0), 5.0,
                                           lambda: gw.land("d1", replace=True))
        _interrupted(third, "move_to", "land")
        assert landed.ok and landed.message.startswith("d1 landed at ("), landed
        assert not ap.in_air and abs(ap.position_m[0]) < 1.0
        assert 70.0 < ap.position_m[1] < 890.0  # where it was when the landing replaced the move

        # With nothing running, replace changes nothing: it is the plain primitive.
        assert (await gw.take_off("d1", 10.0)).ok
        out = await gw.move_to("d1", 10.0, 10.0, 10.0, replace=True)
        assert out.ok and out.message == "d1 reached (10.0, 10.0, 10.0)"
        # A replacing goal that is refused leaves the drone holding, not flying the old goal.
        running, refused = await _hold_during(
            s, gw.move_to("d1", 500.0, 10.0, 10.0), 5.0,
            lambda: gw.move_to("d1", 0.0, 0.0, 500.0, replace=True))
        assert refused.status is Status.REJECTED and "ceiling" in refused.message, refused
        _interrupted(running, "move_to", "move_to")
        await _stays(s, "d1")


@contextlib.asynccontextmanager
async def _lockstep() -> AsyncIterator[tuple[Swarm, SwarmServices, Gateway, Thinker]]:
    scenario = tiny_scenario([vehicle(1)])
    port = unused_udp_port()
    async with Swarm(scenario, clock=ClockConfig(stepped=True, lockstep=True),
                     ports=PortPlan(bind_host="127.0.0.1", api_port=port, gcs_port=0)) as swarm:
        services = SwarmServices(swarm)
        async with await FleetConnection.connect(
                f"udpin://127.0.0.1:{port}", profiles_from_scenario(scenario),
                scenario.world.origin, landed_state_hz=None, timeout_s=30.0) as fleet:
            thinker = Thinker(services)
            try:
                yield swarm, services, Gateway(fleet.drones, services), thinker
            finally:
                thinker.close()


async def test_hold_interrupts_an_agent_waiting_under_the_lockstep_clock():
    # The agent's thread waits on the world (the clock runs only then); an operator's hold
    # from outside that thread ends the wait at once.
    async with _lockstep() as (swarm, services, gw, thinker):
        ap = swarm.fleet.autopilots[0]
        assert (await run_as(thinker, gw.take_off("d1", 10.0))).ok
        stop_s = services.clock_s() + 5.0
        with services.clock_limit(stop_s):  # the clock runs flat out: stop it on the way
            running = run_as(thinker, gw.move_to("d1", 900.0, 0.0, 10.0))
            await _until(lambda: services.clock_s() >= stop_s - 1e-6, "5 s of simulated time")
            hold = await gw.hold("d1")
            out = await asyncio.wait_for(running, PROMPT_WALL_S)
        _interrupted(out, "move_to")
        assert hold.ok and hold.data == {"interrupted": "move_to"}, hold
        assert ap.mode is FlightMode.HOLD and ap.in_air
        assert 5.0 < ap.position_m[0] < 800.0
        back = await run_as(thinker, gw.move_to("d1", 0.0, 0.0, 10.0))
        assert back.ok, back


async def test_hold_on_a_lossy_link_is_never_refused_and_ok_means_holding():
    async with gateway_session(tiny_scenario([vehicle(1)])) as s:
        assert (await s.gw.take_off("d1", 10.0)).ok
        s.swarm.set_link_faults(LinkFaults(seed=3, uplink=LOSSY, downlink=LOSSY))
        ap = s.ap("d1")
        for k in range(5):
            x = 300.0 if k % 2 == 0 else -300.0
            # a lost HOLD or telemetry costs MAVSDK's retransmissions (0.5 s each)
            out, hold = await _hold_during(s, s.gw.move_to("d1", x, 0.0, 10.0), 5.0,
                                           prompt_s=8.0)
            assert out.status in (Status.INTERRUPTED, Status.OK, Status.UNKNOWN), out
            assert hold.status in (Status.OK, Status.UNKNOWN), hold
            if hold.ok:
                assert ap.mode is FlightMode.HOLD and ap.in_air, (hold, ap.mode)
                await _stays(s, "d1")
