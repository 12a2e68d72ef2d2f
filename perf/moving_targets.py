"""Cost of moving targets in the physics loop: MultiUAV-Plat's tracking example (20 drones,
7 moving targets) stepped with and without its targets moving, and the kinematics alone.

    ./dev perf moving_targets [--seconds 600]
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np

from emulator.flight.fleet import Fleet
from emulator.scenario import load_scenario
from emulator.world import World

EXAMPLE = (Path(__file__).resolve().parents[1] / "tests" / "reference"
           / "Example_Session_Target_Tracking.json")


def _steps_per_s(fleet: Fleet, steps: int) -> float:
    started = time.perf_counter()
    for _ in range(steps):
        fleet.step()
    return steps / (time.perf_counter() - started)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=600.0, help="simulated seconds")
    args = parser.parse_args()
    scenario = load_scenario(EXAMPLE)
    still_targets = [dataclasses.replace(t, kind="fixed", motion=None) if t.is_moving else t
                     for t in scenario.world.targets]
    world = scenario.world
    still = dataclasses.replace(scenario, world=World(
        obstacles=world.obstacles, targets=still_targets, wind=world.wind,
        origin=world.origin, safety_margin_m=world.safety_margin_m))
    moving_fleet, still_fleet = Fleet(scenario), Fleet(still)
    steps = round(args.seconds / moving_fleet.dt_s)
    with_rate = _steps_per_s(moving_fleet, steps)
    without_rate = _steps_per_s(still_fleet, steps)
    print(f"fleet.step, 20 drones at rest, {steps} steps: {without_rate:,.0f} steps/s with "
          f"standing targets, {with_rate:,.0f} steps/s with 7 moving "
          f"({1e6 / with_rate - 1e6 / without_rate:.1f} us more per step)")
    targets = moving_fleet.targets
    assert targets is not None
    started = time.perf_counter()
    t = moving_fleet.now_s
    for _ in range(steps):
        targets.advance(t, moving_fleet.dt_s)
        t += moving_fleet.dt_s
    per_step_us = 1e6 * (time.perf_counter() - started) / steps
    legs = sum(targets.legs(i).arrays()[0].size for i in targets.ids)
    started = time.perf_counter()
    for target in targets.ids:
        targets.rows(target, 0.0, t)
    rows_ms = 1e3 * (time.perf_counter() - started)
    times = np.linspace(0.0, t, 100_000)
    started = time.perf_counter()
    targets.legs(targets.ids[0]).positions(times)
    eval_ms = 1e3 * (time.perf_counter() - started)
    print(f"MovingTargets.advance: {per_step_us:.1f} us per physics step for 7 targets; "
          f"{legs} legs over {t:.0f} simulated s; exact rows of all 7: {rows_ms:.2f} ms; "
          f"100,000 positions of one target: {eval_ms:.2f} ms")


if __name__ == "__main__":
    main()
