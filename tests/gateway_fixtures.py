"""Helpers for the gateway tests: a stepped swarm on real UDP with a Gateway connected to it
over MAVSDK, small scenario builders, and ground-truth snapshots to compare outcomes with.

Not a conftest: test modules import what they use.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import time
from collections.abc import AsyncIterator, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from emulator.clock import ClockConfig
from emulator.flight.autopilot import Autopilot
from emulator.scenario import Scenario
from emulator.services import SwarmServices
from emulator.swarm import PortPlan, Swarm
from mavlink_gateway import FleetConnection, Gateway, Outcome, Status, profiles_from_scenario
from mavlink_gateway.drone_link import DroneLink
from mavlink_gateway.flight import ARRIVAL_M
from tests.ports import unused_udp_port

__all__ = [
    "FAST_TELEMETRY_HZ",
    "GatewaySession",
    "Truth",
    "assert_consistent",
    "expect_refusal",
    "gateway_session",
    "max_step_m",
    "near",
    "no_teleport",
    "rejected",
    "same_truth",
    "truth",
]


@dataclass
class GatewaySession:
    scenario: Scenario
    swarm: Swarm
    services: SwarmServices
    fleet: FleetConnection
    gw: Gateway

    def ap(self, drone: str) -> Autopilot:
        return self.swarm.fleet.autopilots[self.swarm.fleet.index_by_id[drone]]

    def link(self, drone: str) -> DroneLink:
        return self.fleet.drones[drone]

    @property
    def now_s(self) -> float:
        return self.services.clock_s()

    async def settle(self, timeout_s: float = 5.0, *, full: bool = True) -> None:
        """Let the stepped clock run out (landing disarm timers, charging) and wait until every
        drone's telemetry cache agrees with the ground truth: position, on-ground and home;
        with `full` also armed, mode (1 Hz heartbeat) and battery (0.5 Hz by default)."""
        await asyncio.wait_for(self.swarm.wait_idle(), timeout_s)
        deadline = time.monotonic() + timeout_s
        while True:
            lagging = [d for d in self.gw.drones if not _telemetry_current(self, d, full)]
            if not lagging:
                return
            if time.monotonic() > deadline:
                raise AssertionError(f"telemetry of {lagging} never caught up with the truth")
            await asyncio.sleep(0.02)


def _telemetry_current(s: GatewaySession, drone: str, full: bool) -> bool:
    ap, link = s.ap(drone), s.link(drone)
    if link.position_m is None or math.dist(link.position_m, ap.position_m) > 0.2:
        return False
    if link.home_m is None or math.dist(link.home_m, ap.home_m) > 0.2:
        return False
    if (link.flight_state == "on_ground") != (not ap.in_air):
        return False
    return not full or (link.armed == ap.armed and link.mode == ap.mode.name
                        and abs(link.battery_pct - ap.battery_pct) < 1.0)


# Faster telemetry than the defaults, so a test waits less for the gateway's cache to catch
# up (armed and mode come with the heartbeat, landed state with EXTENDED_SYS_STATE).
FAST_TELEMETRY_HZ = {"HEARTBEAT": 5.0, "EXTENDED_SYS_STATE": 10.0, "SYS_STATUS": 5.0,
                     "BATTERY_STATUS": 5.0, "HOME_POSITION": 5.0}


@contextlib.asynccontextmanager
async def gateway_session(scenario: Scenario, *,
                          telemetry_hz: Mapping[str, float] | None = FAST_TELEMETRY_HZ,
                          ) -> AsyncIterator[GatewaySession]:
    """A stepped swarm for `scenario` on 127.0.0.1 and a Gateway connected to it over UDP.
    `telemetry_hz`: the swarm's stream rates (None: the emulator's defaults)."""
    port = unused_udp_port()
    ports = PortPlan(bind_host="127.0.0.1", api_port=port, gcs_port=0)
    async with Swarm(scenario, clock=ClockConfig(stepped=True), ports=ports,
                     telemetry_hz=telemetry_hz) as swarm:
        services = SwarmServices(swarm)
        async with await FleetConnection.connect(
            f"udpin://127.0.0.1:{port}", profiles_from_scenario(scenario), scenario.world.origin
        ) as fleet:
            yield GatewaySession(scenario, swarm, services, fleet, Gateway(fleet.drones, services))


@dataclass(frozen=True)
class Truth:
    """One drone's ground truth at one instant."""

    position_m: tuple[float, float, float]
    armed: bool
    in_air: bool
    mode: str
    battery_pct: float
    home_m: tuple[float, float, float]


def truth(s: GatewaySession, drone: str) -> Truth:
    ap = s.ap(drone)
    return Truth(ap.position_m, ap.armed, ap.in_air, ap.mode.name, ap.battery_pct, ap.home_m)


def same_truth(a: Truth, b: Truth) -> bool:
    return (math.dist(a.position_m, b.position_m) < 1e-6 and a.armed == b.armed
            and a.in_air == b.in_air and a.mode == b.mode and a.home_m == b.home_m
            and abs(a.battery_pct - b.battery_pct) < 1e-9)


def assert_consistent(s: GatewaySession, outcome: Outcome, drone: str, *,
                      tolerance_m: float = 3.0) -> None:
    """The state an outcome reports agrees with the drone's ground truth."""
    state = outcome.state
    assert state is not None, outcome
    assert state.drone == drone
    ap = s.ap(drone)
    x, y, z = ap.position_m
    reported = (state.x_m, state.y_m, state.altitude_m + ap.home_m[2])
    assert all(np.isfinite(reported)), state
    assert math.dist(reported, (x, y, z)) <= tolerance_m, (state, ap.position_m)
    assert (state.flight_state == "on_ground") == (z == 0.0), (state, ap.position_m)
    # Not compared: battery (BATTERY_STATUS is 0.5 Hz of wall time, so after a stepped-mode
    # flight it lags by the charge of up to two seconds of wall time, several percent).
    assert 0.0 <= state.battery_pct <= 100.0, state


def rejected(outcome: Outcome, *fragments: str) -> None:
    """The outcome is a refusal whose message says each fragment."""
    assert outcome.status is Status.REJECTED, outcome
    for fragment in fragments:
        assert fragment in outcome.message, (fragment, outcome.message)


async def expect_refusal(s: GatewaySession, call: object, *fragments: str) -> Outcome:
    """Await `call` (a primitive's coroutine, or an Outcome already returned by a synchronous
    primitive, then pass a zero-argument lambda) and check that it was refused with a message
    saying each fragment, and that nothing changed: no drone's truth, no truth event, no
    simulated time."""
    await s.swarm.wait_idle()
    before = {d: truth(s, d) for d in s.gw.drones}
    events = len(s.swarm.recorder.events())
    t0 = s.now_s
    outcome = call() if callable(call) else await call  # type: ignore[misc]
    rejected(outcome, *fragments)
    assert s.now_s == t0, f"{s.now_s - t0} s of simulated time passed during a refusal"
    for drone, was in before.items():
        assert same_truth(truth(s, drone), was), (drone, was, truth(s, drone))
    new = s.swarm.recorder.events()[events:]
    assert not new, f"a refusal recorded truth events: {new}"
    return outcome


def max_step_m(s: GatewaySession, drone: str, t0_s: float, t1_s: float | None = None) -> float:
    """Largest distance between consecutive recorded positions in [t0_s, t1_s]."""
    traj = s.swarm.recorder.trajectory(drone, t0_s, t1_s)
    if len(traj) < 2:
        return 0.0
    return float(np.linalg.norm(np.diff(traj[:, 1:4], axis=0), axis=1).max())


def near(s: GatewaySession, drone: str, point: Sequence[float],
         tol_m: float = ARRIVAL_M) -> None:
    """The drone's true position is within tol_m (default: the gateway's arrival radius)."""
    pos = s.ap(drone).position_m
    assert math.dist(pos, point) <= tol_m, (drone, pos, point)


def no_teleport(s: GatewaySession, drone: str, t0_s: float) -> None:
    """Since t0_s the drone moved at most one physics step of its top 3D speed per step."""
    ap = s.ap(drone)
    top = ap.params["MPC_XY_VEL_MAX"] + math.hypot(*s.swarm.fleet.dyn.wind_m_s) + 4.0
    assert max_step_m(s, drone, t0_s) <= top * s.swarm.fleet.dt_s * 1.01
