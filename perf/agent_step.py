"""Where an LLM agent's step goes: time inside the model call versus outside it (tools,
gateway, flight in stepped time, agent logic), with a scripted model in process that answers
at once, so the outside share is the platform's own cost per step.

    ./dev perf agent_step [--tasks 5]
"""

from __future__ import annotations

import argparse
import asyncio
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmark.authoring.session_file import session_from_dict
from benchmark.running.episode import run_session
from swarm_agents.llm import ModelReply, ReactAgent, ScriptedChatModel
from swarm_agents.llm import tool_call as call
from swarm_agents.llm.scripted import Reply
from tests.bench_fixtures import small_session


class TimedModel:
    """A `ChatModel` that counts the calls to another and the time spent in them."""

    def __init__(self, model: ScriptedChatModel) -> None:
        self.model = model
        self.in_model_s = 0.0
        self.calls = 0

    async def complete(self, messages: Sequence[Mapping[str, Any]],
                       tools: Sequence[Mapping[str, Any]]) -> ModelReply:
        started = time.perf_counter()
        try:
            return await self.model.complete(messages, tools)
        finally:
            self.in_model_s += time.perf_counter() - started
            self.calls += 1

    async def close(self) -> None:
        await self.model.close()


async def main(tasks: int) -> None:
    keys = ["takeoff_hold", "climb_and_face", "altitude_change"]
    data = small_session((keys * (tasks // len(keys) + 1))[:tasks])
    session = session_from_dict(data, source="bench")
    script: list[Reply] = []
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
    model = TimedModel(ScriptedChatModel(script))
    records: list[dict] = []
    await run_session(session, ReactAgent(model), emit=records.append)
    in_model, steps = model.in_model_s, model.calls
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
