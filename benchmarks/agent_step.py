"""Where an LLM agent's step goes: time inside the model call versus outside it (tools,
gateway, flight in stepped time, agent logic), with a scripted model that answers at once, so
the outside share is the platform's own cost per step.

    ./dev bench agent_step [--tasks 5]
"""

from __future__ import annotations

import argparse
import asyncio
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from agents.llm import ModelConfig, ReactAgent
from agents.llm.openai_model import ChatClient
from benchmark.episode import run_session
from benchmark.session_file import session_from_dict
from tests.bench_fixtures import small_session
from tests.scripted_llm import call, scripted_llm


async def main(tasks: int) -> None:
    keys = ["takeoff_hold", "climb_and_face", "altitude_change"]
    data = small_session((keys * (tasks // len(keys) + 1))[:tasks])
    session = session_from_dict(data, source="bench")
    script: list[object] = []
    for task in data["tasks"]:  # the oracle's plan, replayed as a model's tool calls
        for op in task["oracle"][0]:
            if op["op"] == "takeoff":
                script.append([call("take_off", {"drone_id": op["drone"],
                                                 "altitude_m": op["altitude_m"]})])
            elif op["op"] == "rotate":
                script.append([call("rotate", {"drone_id": op["drone"],
                                               "heading_deg": op["heading_deg"]})])
            elif op["op"] == "altitude":
                script.append([call("change_altitude", {"drone_id": op["drone"],
                                                        "altitude_m": op["altitude_m"]})])
        script.append([call("finish", {})])
    in_model = 0.0
    steps = 0
    original = ChatClient.complete

    async def timed(self, messages, tools):  # type: ignore[no-untyped-def]
        nonlocal in_model, steps
        t = time.perf_counter()
        try:
            return await original(self, messages, tools)
        finally:
            in_model += time.perf_counter() - t
            steps += 1

    ChatClient.complete = timed  # type: ignore[method-assign]
    records: list[dict] = []
    with scripted_llm(script) as llm:
        agent = ReactAgent(ModelConfig(base_url=llm.base_url, model="scripted", api_key="k"))
        await run_session(session, agent, emit=records.append)
    total = sum(r["wall_time_s"] for r in records)
    outside = total - in_model
    print(f"{len(records)} tasks, {sum(r['passed'] for r in records)} passed, {steps} model "
          f"calls; agent wall {total:.2f} s: in the model call {in_model:.2f} s "
          f"({1000 * in_model / steps:.1f} ms per call, scripted), outside {outside:.2f} s "
          f"({1000 * outside / steps:.1f} ms per step, {100 * outside / total:.0f} %)")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--tasks", type=int, default=5)
    asyncio.run(main(parser.parse_args().tasks))
