"""Tool-call overhead of the LLM tool registry (schema validation, JSON arguments, result
encoding) over calling the agent tools directly, on a live stepped swarm.

    ./dev perf tool_latency [--calls 300]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import pct

from agent_contract import AgentTask, AgentTools, TaskBudget
from benchmark.authoring.session_file import session_from_dict
from benchmark.running.episode import swarm_gateway
from llm_tools import default_registry
from tests.bench_fixtures import small_session


def _ms(samples: list[float]) -> str:
    return f"p50 {pct(samples, 50) * 1000:.3f} ms  p95 {pct(samples, 95) * 1000:.3f} ms"


async def main(calls: int) -> None:
    session = session_from_dict(small_session(["takeoff_hold"]), source="bench")
    registry = default_registry()
    async with swarm_gateway(session) as (_swarm, _services, gateway):
        task = AgentTask("bench", "t", "bench", TaskBudget(10 * calls + 100, 1e9))
        tools = AgentTools(gateway, task)
        drone = tools.drone_ids[0]
        cases = {
            "drone_state": (lambda: tools.drone_state(drone), json.dumps({"drone_id": drone})),
            "nearby": (lambda: tools.nearby(drone), json.dumps({"drone_id": drone})),
            "list_drones": (tools.list_drones, "{}"),
        }
        for name, (direct, args) in cases.items():
            d, r = [], []
            for _ in range(calls):
                t = time.perf_counter()
                json.dumps(direct().to_dict())
                d.append(time.perf_counter() - t)
                t = time.perf_counter()
                json.dumps(await registry.call(tools, name, args))
                r.append(time.perf_counter() - t)
            extra = [b - a for a, b in zip(sorted(d), sorted(r), strict=True)]
            print(f"{name:<12} direct {_ms(d)} | registry {_ms(r)} | added p50 "
                  f"{statistics.median(extra) * 1000:.3f} ms")
        bad = []
        for _ in range(calls):
            t = time.perf_counter()
            await registry.call(tools, "take_off", '{"drone_id": 3, "altitude_m": "x"}')
            bad.append(time.perf_counter() - t)
        print(f"{'rejected':<12} registry {_ms(bad)} (validation error, nothing sent)")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--calls", type=int, default=300)
    asyncio.run(main(parser.parse_args().calls))
