"""The gateway over faulty links and with failed vehicles, through real MAVSDK over UDP, on a
lockstep clock: outcomes stay correct (or say they are unknown), and the truth is the same on
every run with the same seed."""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections.abc import AsyncIterator, Awaitable
from typing import Any, TypeVar

import numpy as np
import pytest
from mavsdk.asyncio.plugins.failure import FailureAsync
from mavsdk.plugins.failure import FailureError, FailureType, FailureUnit

from emulator.clock import ClockConfig
from emulator.link_faults import LinkFaults, LinkProfile
from emulator.services import SwarmServices
from emulator.swarm import PortPlan, Swarm
from mavlink_gateway import FleetConnection, Gateway, Status, profiles_from_scenario
from mavlink_gateway.lockstep_wait import wait_world
from mavlink_gateway.pacing import Thinker, run_as
from tests.ports import unused_udp_port
from tests.scenario_fixtures import tiny_scenario, vehicle

pytestmark = pytest.mark.mavsdk

T = TypeVar("T")
RATES = {"HEARTBEAT": 1.0, "EXTENDED_SYS_STATE": 1.0, "SYS_STATUS": 1.0,
         "BATTERY_STATUS": 1.0, "HOME_POSITION": 0.5, "GLOBAL_POSITION_INT": 2.0}
LOSSY = LinkProfile(loss=0.2, latency_ms=50.0, jitter_ms=20.0)


@contextlib.asynccontextmanager
async def lockstep_gateway(n: int, faults: LinkFaults | None = None
                           ) -> AsyncIterator[tuple[Swarm, SwarmServices, Gateway, Thinker]]:
    scenario = tiny_scenario([vehicle(k + 1, x=40.0 * k) for k in range(n)])
    port = unused_udp_port()
    async with Swarm(scenario, clock=ClockConfig(stepped=True, lockstep=True),
                     ports=PortPlan(bind_host="127.0.0.1", api_port=port, gcs_port=0),
                     telemetry_hz=RATES, link_faults=faults) as swarm:
        services = SwarmServices(swarm)
        async with await FleetConnection.connect(
                f"udpin://127.0.0.1:{port}", profiles_from_scenario(scenario),
                scenario.world.origin, landed_state_hz=None, timeout_s=30.0) as fleet:
            thinker = Thinker(services)
            try:
                yield swarm, services, Gateway(fleet.drones, services), thinker
            finally:
                thinker.close()


async def act(thinker: Thinker, call: Awaitable[T]) -> T:
    """Run a call as the agent's one thread of control (lockstep: it pins the clock)."""
    return await run_as(thinker, call)


async def _chain(seed: int) -> tuple[list[str], list[Any], np.ndarray, int]:
    faults = LinkFaults(seed=seed, uplink=LOSSY, downlink=LOSSY)
    async with lockstep_gateway(1, faults) as (swarm, _services, gw, thinker):
        statuses = []
        for call in (gw.take_off("d1", 10.0), gw.move_to("d1", 120.0, 0.0, 10.0),
                     gw.take_photo("d1"), gw.take_photo("d1"), gw.land("d1")):
            outcome = await act(thinker, call)
            statuses.append(outcome.status.value)
        events = [(round(e.t_s, 6), e.vehicle_id, e.kind, e.to_json())
                  for e in swarm.recorder.events()]
        trajectory = np.asarray(swarm.recorder.trajectory("d1"))
        return statuses, events, trajectory, swarm.fleet.autopilots[0].photo_count


async def test_primitives_reach_correct_outcomes_and_the_same_truth_on_a_lossy_link() -> None:
    first = await _chain(seed=11)
    second = await _chain(seed=11)
    assert first[0] == ["ok"] * 5
    assert first[3] == 2  # two photos asked, two taken: no retransmission took a third
    assert second[0] == first[0]
    assert second[1] == first[1]
    assert second[2].tobytes() == first[2].tobytes()


async def test_an_unanswered_command_is_unknown_never_a_refusal() -> None:
    async with lockstep_gateway(1) as (swarm, _services, gw, thinker):
        swarm.set_link_faults(LinkFaults.from_json({"uplink": {"loss": 1.0}}))
        start = time.monotonic()
        outcome = await act(thinker, gw.take_off("d1", 10.0))
        assert outcome.status is Status.UNKNOWN, outcome
        assert "no answer from d1" in outcome.message
        assert outcome.state is not None and outcome.state.flight_state == "on_ground"
        assert time.monotonic() - start < 30.0
        assert not swarm.fleet.autopilots[0].armed  # nothing reached it: nothing happened


async def _inject(gw: Gateway, drone: str, unit: FailureUnit, kind: FailureType) -> None:
    await FailureAsync(gw.drones[drone].system).inject(unit, kind, 0)


async def _until(condition: Any, timeout_s: float = 5.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, "condition not reached"
        await asyncio.sleep(0.02)


async def test_injected_failures_as_px4_answers_them() -> None:
    async with lockstep_gateway(3) as (swarm, services, gw, thinker):
        aps = swarm.fleet.autopilots
        for drone in ("d1", "d2", "d3"):
            assert (await act(thinker, gw.take_off(drone, 15.0))).ok
        with pytest.raises(FailureError):  # SYS_FAILURE_EN = 0 (PX4's default)
            await _inject(gw, "d1", FailureUnit.SYSTEM_MOTOR, FailureType.OFF)
        assert not aps[0].failures.any
        for drone in ("d1", "d2", "d3"):
            await gw.drones[drone].param.set_param_int("SYS_FAILURE_EN", 1)
        with pytest.raises(FailureError) as unsupported:
            await _inject(gw, "d1", FailureUnit.SENSOR_GYRO, FailureType.OFF)
        assert unsupported.value.result.name == "UNSUPPORTED"

        # motor off: the drone comes down and is out; its primitives say so
        await _inject(gw, "d1", FailureUnit.SYSTEM_MOTOR, FailureType.OFF)
        await _until(lambda: gw.drones["d1"].failure is not None)
        outcome = await act(thinker, gw.move_to("d1", 50.0, 50.0, 15.0))
        assert outcome.status is Status.FAILED and "Motor failure" in outcome.message
        assert outcome.state is not None and outcome.state.flight_state == "failed"

        # battery: a sudden drop to critical, and the battery failsafe returns it home
        await _inject(gw, "d2", FailureUnit.SYSTEM_BATTERY, FailureType.OFF)
        assert aps[1].mode.name == "RTL" and aps[1].battery_pct < 7.0

        # MAVLink signal off: silent, it keeps flying; a primitive for it ends, unknown
        await _inject(gw, "d3", FailureUnit.SYSTEM_MAVLINK_SIGNAL, FailureType.OFF)
        outcome = await act(thinker, gw.move_to("d3", 80.0, 40.0, 15.0))
        assert outcome.status is Status.UNKNOWN, outcome
        assert aps[2].in_air

        await act(thinker, wait_world(services, "d1", 60.0))
        assert not aps[0].in_air and not aps[0].armed
        with pytest.raises(Exception, match="motor failure"):
            aps[0].arm()
        kinds = {(e.vehicle_id, e.kind, e.data.get("unit") or e.data.get("reason"))
                 for e in swarm.recorder.events() if e.kind in ("failure", "failsafe")}
        assert {("d1", "failure", "motor"), ("d1", "failsafe", "motor_failure"),
                ("d2", "failure", "battery"), ("d2", "failsafe", "battery_critical"),
                ("d3", "failure", "mavlink")} <= kinds
        assert any(e.kind == "link_lost" and e.vehicle_id == "d3"
                   for e in swarm.recorder.events())

        services.operator_land_all()  # the operator's reset between tasks repairs them
        assert not any(ap.failures.any for ap in aps)


async def test_a_task_schedules_hidden_failures_and_link_faults_from_its_start() -> None:
    import copy
    import json

    from benchmark.authoring.session_file import session_from_dict
    from benchmark.running.episode import EpisodeOptions, run_task, swarm_gateway
    from swarm_agents.oracle import OracleAgent
    from tests.cli_fixtures import ROOT

    path = ROOT / "benchmark" / "sessions" / "target_assignment-easy-1.json"
    data = json.loads(path.read_text())
    data["tasks"] = copy.deepcopy(data["tasks"][:2])  # t01: d2 takes off to 13 m and holds
    data["tasks"][0]["faults"] = {"failures": [{"drone": "d2", "after_s": 3, "unit": "motor"}],
                                  "link": {"loss": 0.1, "seed": 5}}
    session = session_from_dict(data, source="resilience-test")
    agent = OracleAgent(session.scenario, {t.id: t.oracle for t in session.tasks})
    async with swarm_gateway(session, lockstep=True) as (swarm, services, gateway):
        t0 = services.clock_s()
        record = await run_task(session, session.tasks[0], agent, swarm, services, gateway,
                                EpisodeOptions())
        # the record's own start is after the reset; the failure comes 3 s into the task
        failure = next(e for e in swarm.recorder.events() if e.kind == "failure")
        assert (failure.vehicle_id, failure.data["unit"], failure.data["source"]) == \
            ("d2", "motor", "schedule")
        faults_events = [e for e in swarm.recorder.events() if e.kind == "link_faults"]
        assert [e.data["uplink"]["loss"] for e in faults_events if e.vehicle_id == "d2"] == \
            [0.1, 0.0]  # the task's link, then the session's clean link again
        start = faults_events[0].t_s
        assert start >= t0 and round(failure.t_s - start, 6) == 3.0
        assert record["passed"] is False and record["finish"] == "finished"
        second = await run_task(session, session.tasks[1], agent, swarm, services, gateway,
                                EpisodeOptions())
        assert second["finish"] == "finished"
        assert any(e.kind == "operator_repair" and e.vehicle_id == "d2"
                   for e in swarm.recorder.events())
        assert not swarm.fleet.autopilots[1].failures.any
