"""CPU time to read a session's entities (drones, targets, obstacles) into a scenario.

    ./dev perf scenario_parse [--sizes 250,1000,5000] [--repeat 5]

Builds a MultiUAV-Plat-style session object with N drones (on a 10 m grid), N/10 targets of
each kind and N/50 obstacles of each kind, then times `emulator.scenario.scenario_from_dict` on
it (validation, the reference mappings, uniqueness and placement checks). CPU is this process's
CPU time (time.process_time), the best of `--repeat` runs.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from typing import Any

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _common import machine_line, table

from emulator.scenario import scenario_from_dict


def session(n: int) -> dict[str, Any]:
    """A session object with n drones, n/10 targets of each kind, n/50 obstacles of each."""
    side = int(n**0.5) + 1
    drones = [{"id": f"d{k}", "name": f"Drone {k}", "model": "M", "max_speed": 12,
               "max_altitude": 120, "battery_capacity": 80, "battery_level": 90,
               "position": {"x": 10.0 * (k % side), "y": 10.0 * (k // side), "z": 0},
               "home_position": {"x": 10.0 * (k % side), "y": 10.0 * (k // side)}}
              for k in range(n)]
    far = 10.0 * side + 200.0
    targets: list[dict[str, Any]] = []
    for k in range(max(1, n // 10)):
        x, y = far + 30.0 * k, 0.0
        targets += [
            {"id": f"f{k}", "name": "F", "type": "fixed", "position": {"x": x, "y": y}},
            {"id": f"c{k}", "name": "C", "type": "circle", "radius": 5,
             "position": {"x": x, "y": y + 40}},
            {"id": f"w{k}", "name": "W", "type": "waypoint", "position": {"x": x, "y": y + 80}},
            {"id": f"m{k}", "name": "M", "type": "moving", "position": {"x": x, "y": y + 120},
             "velocity": {"x": 0.5, "y": 0, "z": 0}, "moving_duration": 5},
            {"id": f"p{k}", "name": "P", "type": "polygon",
             "vertices": [{"x": x, "y": y + 160}, {"x": x + 10, "y": y + 160},
                          {"x": x + 10, "y": y + 170}]},
        ]
    obstacles: list[dict[str, Any]] = []
    for k in range(max(1, n // 50)):
        x, y = -far - 40.0 * k, 0.0
        obstacles += [
            {"id": f"op{k}", "name": "P", "type": "point", "position": {"x": x, "y": y}},
            {"id": f"oc{k}", "name": "C", "type": "circle", "radius": 5,
             "position": {"x": x, "y": y + 40}},
            {"id": f"oe{k}", "name": "E", "type": "ellipse", "width": 6, "length": 9,
             "position": {"x": x, "y": y + 80}},
            {"id": f"oq{k}", "name": "Q", "type": "polygon", "height": 20,
             "vertices": [{"x": x, "y": y + 120}, {"x": x + 10, "y": y + 120},
                          {"x": x + 10, "y": y + 130}, {"x": x, "y": y + 130}]},
        ]
    return {"name": f"parse-{n}", "task_type": "others", "drones": drones, "targets": targets,
            "obstacles": obstacles, "environment": {"wind_speed": 2, "wind_direction": "east"}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", default="250,1000,5000")
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    rows = []
    for n in (int(s) for s in args.sizes.split(",")):
        data = session(n)
        best = float("inf")
        for _ in range(args.repeat):
            start = time.process_time()
            scenario = scenario_from_dict(data, source=f"parse-{n}")
            best = min(best, time.process_time() - start)
        entities = len(scenario.vehicles) + len(scenario.world.targets) + len(
            scenario.world.obstacles)
        rows.append((n, entities, f"{best * 1e3:.1f}", f"{best / entities * 1e6:.1f}"))
    print(machine_line())
    print(table(("drones", "entities", "CPU ms (best)", "us per entity"), rows))


if __name__ == "__main__":
    main()
