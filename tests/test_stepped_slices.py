"""How far a stepped swarm's scheduler steps at once: a lockstep clock in slices of
STEPS_PER_SLICE (where its slices end is part of every result), a stepped clock without
lockstep in longer ones (it runs flat out; its slices already end wherever datagrams arrive),
looking at its sockets at least every FREE_SIM_S_PER_LOOK of simulated time."""

from __future__ import annotations

import itertools

import pytest

from emulator.clock import ClockConfig
from emulator.port_plan import PortPlan
from emulator.swarm import FREE_SIM_S_PER_LOOK, FREE_STEPS_PER_SLICE, STEPS_PER_SLICE, Swarm
from tests.ports import unused_udp_port
from tests.scenario_fixtures import tiny_scenario, vehicle

CLIMB_TO_M = 110.0  # a climb of well over FREE_SIM_S_PER_LOOK


async def _slices_of_a_long_climb(clock: ClockConfig) -> tuple[list[int], list[int], float]:
    """While one vehicle climbs to CLIMB_TO_M: the max_steps of every fleet.run, the step
    count at every look of the scheduler, and the altitude reached."""
    ports = PortPlan(bind_host="127.0.0.1", bind_port=0, api_port=unused_udp_port(), gcs_port=0)
    async with Swarm(tiny_scenario([vehicle(1)]), clock=clock, ports=ports) as swarm:
        fleet = swarm.fleet
        asked: list[int] = []
        looks: list[int] = []
        run, slicing = fleet.run, swarm._slicing

        def run_spy(max_steps: int, *, fast_forward: bool = True) -> int:
            asked.append(max_steps)
            return run(max_steps, fast_forward=fast_forward)

        def slicing_spy() -> tuple[int, int]:
            looks.append(fleet.step_count)
            return slicing()

        fleet.run = run_spy  # type: ignore[method-assign]
        swarm._slicing = slicing_spy  # type: ignore[method-assign]
        autopilot = fleet.autopilots[0]
        autopilot.arm()
        autopilot.takeoff(CLIMB_TO_M)
        swarm.wake()
        await swarm.wait_idle()
        looks.append(fleet.step_count)
        return asked, looks, float(fleet.dyn.position_m[0, 2])


@pytest.mark.parametrize("lockstep", [True, False])
async def test_only_a_lockstep_clock_keeps_its_short_slices(lockstep: bool) -> None:
    clock = ClockConfig(stepped=True, lockstep=lockstep)
    asked, looks, altitude_m = await _slices_of_a_long_climb(clock)
    assert altitude_m == pytest.approx(CLIMB_TO_M, abs=0.5)
    assert asked and min(asked) >= 1
    if lockstep:
        assert max(asked) == STEPS_PER_SLICE
    else:
        assert max(asked) == FREE_STEPS_PER_SLICE > STEPS_PER_SLICE
        # However fast the machine, the scheduler looks at its sockets again within
        # FREE_SIM_S_PER_LOOK of simulated time.
        look_steps = round(FREE_SIM_S_PER_LOOK * clock.physics_hz)
        assert looks[-1] - looks[0] > 2 * look_steps  # the climb outlasts several looks
        assert max(b - a for a, b in itertools.pairwise(looks)) <= look_steps
