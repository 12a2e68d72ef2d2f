"""How far a stepped swarm's scheduler steps at once: a lockstep clock in slices of
STEPS_PER_SLICE (where its slices end is part of every result), a stepped clock without
lockstep in longer ones (it runs flat out; its slices already end wherever datagrams arrive)."""

from __future__ import annotations

import pytest

from emulator.clock import ClockConfig
from emulator.port_plan import PortPlan
from emulator.swarm import FREE_STEPS_PER_SLICE, STEPS_PER_SLICE, Swarm
from tests.ports import unused_udp_port
from tests.scenario_fixtures import tiny_scenario, vehicle

CLIMB_TO_M = 110.0  # a climb of well over FREE_STEPS_PER_SLICE steps


async def _slices_of_a_long_climb(clock: ClockConfig) -> tuple[list[int], float]:
    """The max_steps of every fleet.run while one vehicle climbs to CLIMB_TO_M, and the
    altitude it reached."""
    ports = PortPlan(bind_host="127.0.0.1", bind_port=0, api_port=unused_udp_port(), gcs_port=0)
    async with Swarm(tiny_scenario([vehicle(1)]), clock=clock, ports=ports) as swarm:
        fleet = swarm.fleet
        asked: list[int] = []
        run = fleet.run

        def spy(max_steps: int, *, fast_forward: bool = True) -> int:
            asked.append(max_steps)
            return run(max_steps, fast_forward=fast_forward)

        fleet.run = spy  # type: ignore[method-assign]
        autopilot = fleet.autopilots[0]
        autopilot.arm()
        autopilot.takeoff(CLIMB_TO_M)
        swarm.wake()
        await swarm.wait_idle()
        return asked, float(fleet.dyn.position_m[0, 2])


@pytest.mark.parametrize("lockstep", [True, False])
async def test_only_a_lockstep_clock_keeps_its_short_slices(lockstep: bool) -> None:
    asked, altitude_m = await _slices_of_a_long_climb(ClockConfig(stepped=True,
                                                                  lockstep=lockstep))
    assert altitude_m == pytest.approx(CLIMB_TO_M, abs=0.5)
    assert asked and min(asked) >= 1
    if lockstep:
        assert max(asked) == STEPS_PER_SLICE
    else:
        assert max(asked) == FREE_STEPS_PER_SLICE > STEPS_PER_SLICE
