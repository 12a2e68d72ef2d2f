"""The scripted `ChatModel` in process: replies from a list (messages, tool calls, text,
failures) or from a function of the request, `finish` once a list runs out, every request kept
as the wire would carry it; and the LLM agents driven by it without a server or a swarm."""

from __future__ import annotations

import asyncio
import json
from typing import Any

import pytest

from agent_contract import AgentTask, TaskBudget
from mavlink_gateway import Outcome, Status
from swarm_agents.llm import (
    ChatModel,
    ModelError,
    ReactAgent,
    ScriptedChatModel,
    Usage,
    WorkflowAgent,
    tool_call,
)
from swarm_agents.llm.scripted import SCRIPTED_USAGE, ScriptedRequest

USER = [{"role": "user", "content": "hello"}]
TOOL = {"type": "function", "function": {"name": "land", "parameters": {"type": "object"}}}


async def test_a_list_script_answers_in_order_then_finishes() -> None:
    model = ScriptedChatModel([
        {"content": "thinking"},
        [tool_call("land", {"drone_id": "d1"}, "c1")],
        "plain text",
        [tool_call("take_off", "{not json", "c2")],
    ])
    assert isinstance(model, ChatModel)
    replies = [await model.complete(USER, [TOOL]) for _ in range(5)]
    messages = [r.message for r in replies]
    assert messages[0] == {"role": "assistant", "content": "thinking"}
    assert messages[1] == {"role": "assistant", "content": "", "tool_calls": [
        {"id": "c1", "type": "function",
         "function": {"name": "land", "arguments": '{"drone_id": "d1"}'}}]}
    assert messages[2] == {"role": "assistant", "content": "plain text"}
    assert messages[3]["tool_calls"][0]["function"]["arguments"] == "{not json"
    assert messages[4]["tool_calls"][0]["function"] == {
        "name": "finish", "arguments": '{"summary": "script ended"}'}
    assert all(r.usage == SCRIPTED_USAGE == Usage(100, 20) for r in replies)
    assert model.remaining == 0 and len(model.requests) == 5


async def test_requests_are_kept_as_sent_and_unsendable_ones_fail() -> None:
    model = ScriptedChatModel([], usage=Usage(3, 4, 0.5))
    conversation: list[dict[str, Any]] = list(USER)
    reply = await model.complete(conversation, [TOOL])
    conversation.append({"role": "assistant", "content": "later"})
    assert model.requests == [ScriptedRequest(USER, [TOOL])]  # a copy, not the live list
    assert reply.usage == Usage(3, 4, 0.5)
    with pytest.raises(TypeError, match="not JSON serializable"):
        await model.complete([{"role": "user", "content": object()}], [])


async def test_a_failure_in_the_script_is_raised() -> None:
    model = ScriptedChatModel([ModelError("the model backend failed once: HTTP 503")])
    with pytest.raises(ModelError, match="HTTP 503"):
        await model.complete(USER, [])
    with pytest.raises(TypeError, match="not int"):
        await ScriptedChatModel([7]).complete(USER, [])  # type: ignore[list-item]


async def test_a_function_script_answers_each_request_sync_or_async() -> None:
    def echo(request: ScriptedRequest) -> str:
        return f"{len(request.messages)} messages, {len(request.tools)} tools"

    async def later(request: ScriptedRequest) -> list[dict[str, Any]]:
        await asyncio.sleep(0)
        return [tool_call("finish", {"summary": request.messages[-1]["content"]})]

    assert (await ScriptedChatModel(echo).complete(USER, [TOOL])).message["content"] == \
        "1 messages, 1 tools"
    finish = (await ScriptedChatModel(later).complete(USER, [])).message["tool_calls"][0]
    assert json.loads(finish["function"]["arguments"]) == {"summary": "hello"}


async def test_think_time_is_awaited_before_each_answer() -> None:
    waits: list[float] = []

    def think_s() -> float:
        waits.append(0.01)
        return 0.01

    model = ScriptedChatModel(["a", "b"], think_s=think_s)
    loop = asyncio.get_running_loop()
    started = loop.time()
    await model.complete(USER, [])
    await model.complete(USER, [])
    assert waits == [0.01, 0.01] and loop.time() - started >= 0.02


class _Tools:
    """Just enough of `AgentTools` for model turns, sensing and `finish`, without a swarm."""

    drone_ids = ["d1"]

    def __init__(self) -> None:
        self.finished = False
        self.summary = ""
        self.prompt_tokens = self.completion_tokens = 0
        self.cost_usd = 0.0
        self.transcript: list[tuple[str, str]] = []

    def add_tokens(self, prompt: int, completion: int, cost_usd: float = 0.0) -> None:
        self.prompt_tokens += prompt
        self.completion_tokens += completion
        self.cost_usd += cost_usd

    def add_transcript(self, role: str, content: str, **fields: Any) -> None:
        self.transcript.append((role, content))

    def finish(self, summary: str = "") -> Outcome:
        self.finished, self.summary = True, summary
        return Outcome(Status.OK, "finished")

    def list_drones(self) -> Outcome:
        return Outcome(Status.OK, "1 drones", data={"drones": [{"drone": "d1"}]})

    def nearby(self, drone_id: str) -> Outcome:
        return Outcome(Status.OK, "nothing near", data={"targets": [], "obstacles": []})

    async def concurrently(self, *calls: Any) -> list[Any]:
        return list(await asyncio.gather(*calls, return_exceptions=True))


TASK = AgentTask("s", "t1", "Land d1.", TaskBudget(tool_calls=10, sim_time_s=60.0))


async def test_the_react_agent_stops_after_three_text_answers_and_prices_its_turns() -> None:
    model = ScriptedChatModel(["one", "two", "three", "never asked"], usage=Usage(10, 5, 0.25))
    tools = _Tools()
    await ReactAgent(model).run(TASK, tools)  # type: ignore[arg-type]
    assert tools.summary == ("stopped: the model answered without a tool call 3 times (text "
                             "instead of tool calls)")
    assert (tools.prompt_tokens, tools.completion_tokens, tools.cost_usd) == (30, 15, 0.75)
    assert model.remaining == 1 and not model.closed  # the caller owns the model
    assert [m["content"] for m in model.requests[-1].messages[2:]] == [
        "one", "Act with the tools; call finish when the whole task is done.", "two",
        "Act with the tools; call finish when the whole task is done."]
    assert [role for role, _ in tools.transcript] == [
        "system", "user", "assistant", "user", "assistant", "user", "assistant"]


async def test_the_workflow_agent_reports_a_model_failure() -> None:
    model = ScriptedChatModel([ModelError("the model backend failed once: HTTP 500")])
    tools = _Tools()
    with pytest.raises(ModelError, match="HTTP 500"):
        await WorkflowAgent(model).run(TASK, tools)  # type: ignore[arg-type]
    assert len(model.requests) == 1 and not tools.finished
    assert "Blackboard: " in model.requests[0].messages[1]["content"]
