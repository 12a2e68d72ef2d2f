"""The `ChatModel` over the OpenAI SDK (`OpenAIChatModel`) against a real HTTP server that
answers from a script: what it sends, what it retries, and what it gives back (token use
priced); and the assistant message the agents send back into the conversation."""

from __future__ import annotations

import json
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

import pytest

from llm_tools.openai_adapter import parse_tool_calls
from swarm_agents.llm import ChatModel, ModelConfig, ModelError, OpenAIChatModel, Usage
from swarm_agents.llm.react import assistant_message
from tests.ports import unused_tcp_port

USER = [{"role": "user", "content": "hello"}]


def _completion(message: Any, usage: Any = None) -> tuple[int, str]:
    body: dict[str, Any] = {"id": "c", "object": "chat.completion", "created": 0, "model": "m",
                            "choices": [{"index": 0, "message": message,
                                         "finish_reason": "stop"}]}
    if usage is not None:
        body["usage"] = usage
    return 200, json.dumps(body)


ANSWER = _completion({"role": "assistant", "content": "hi"},
                     {"prompt_tokens": 7, "completion_tokens": 3, "total_tokens": 10})


@dataclass
class Recorded:
    replies: list[tuple[int, str]]
    headers: list[dict[str, str]] = field(default_factory=list)
    bodies: list[dict[str, Any]] = field(default_factory=list)
    base_url: str = ""


@contextmanager
def server(replies: list[tuple[int, str]]) -> Iterator[Recorded]:
    """Answers each POST to /v1/chat/completions with the next (status, body)."""
    recorded = Recorded(list(replies))

    class Handler(BaseHTTPRequestHandler):
        def do_POST(self) -> None:
            length = int(self.headers.get("Content-Length", "0"))
            recorded.headers.append({k.lower(): v for k, v in self.headers.items()})
            recorded.bodies.append(json.loads(self.rfile.read(length) or b"{}"))
            status, body = recorded.replies.pop(0) if recorded.replies else ANSWER
            data = body.encode()
            self.send_response(status)
            self.send_header("Content-Type", "application/json")
            self.send_header("Content-Length", str(len(data)))
            self.end_headers()
            self.wfile.write(data)

        def log_message(self, *args: Any) -> None:
            pass

    httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    recorded.base_url = f"http://127.0.0.1:{httpd.server_address[1]}/v1"
    try:
        yield recorded
    finally:
        httpd.shutdown()
        httpd.server_close()


async def _complete(base_url: str, tools: list[Any] | None = None,
                    **config: Any) -> tuple[dict[str, Any], dict[str, int]]:
    client = OpenAIChatModel(ModelConfig(base_url=base_url, model="m", **config))
    assert isinstance(client, ChatModel)
    try:
        reply = await client.complete(USER, tools or [])
    finally:
        await client.close()
    return reply.message, reply.usage.tokens()


async def test_an_answer_comes_back_with_its_token_use_and_the_request_is_complete(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("OPENAI_API_KEY", raising=False)
    tool = {"type": "function", "function": {"name": "land", "parameters": {"type": "object"}}}
    with server([]) as llm:
        message, usage = await _complete(llm.base_url, [tool], max_completion_tokens=12,
                                         temperature=0.5)
        await _complete(llm.base_url)
    assert message == {"role": "assistant", "content": "hi"}
    assert usage == {"prompt": 7, "completion": 3}
    first, second = llm.bodies
    assert first["model"] == "m" and first["messages"] == USER
    assert first["tools"] == [tool] and first["max_tokens"] == 12
    assert first["temperature"] == 0.5
    assert "tools" not in second and "max_tokens" not in second


async def test_token_use_is_priced_per_million_tokens() -> None:
    with server([]) as llm:
        client = OpenAIChatModel(ModelConfig(base_url=llm.base_url, model="m",
                                             price_in_usd_per_mtok=2.0,
                                             price_out_usd_per_mtok=8.0))
        try:
            reply = await client.complete(USER, [])
        finally:
            await client.close()
    assert reply.usage == Usage(prompt=7, completion=3, cost_usd=(7 * 2.0 + 3 * 8.0) / 1e6)


async def test_a_key_is_sent_as_a_bearer_token_and_no_key_sends_no_authorization(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("OPENAI_API_KEY", raising=False)
    with server([]) as llm:
        await _complete(llm.base_url, api_key="sk-test")
        await _complete(llm.base_url)
        monkeypatch.setenv("OPENAI_API_KEY", "sk-from-env")
        await _complete(llm.base_url)
    assert [h.get("authorization") for h in llm.headers] == [
        "Bearer sk-test", None, "Bearer sk-from-env"]


@pytest.mark.slow
async def test_server_errors_are_retried_then_end_in_a_model_error() -> None:
    with server([(500, "upstream hiccup"), ANSWER]) as llm:
        message, _ = await _complete(llm.base_url, retries=2)
    assert message["content"] == "hi" and len(llm.bodies) == 2
    with (server([(503, "overloaded")] * 3) as llm,
          pytest.raises(ModelError, match=r"failed 2 times: HTTP 503: overloaded")):
        await _complete(llm.base_url, retries=1)
    assert len(llm.bodies) == 2


async def test_a_refused_request_is_not_retried() -> None:
    with (server([(400, '{"error": {"message": "context too long"}}')]) as llm,
          pytest.raises(ModelError, match=r"^HTTP 400: .*context too long")):
        await _complete(llm.base_url, retries=3)
    assert len(llm.bodies) == 1


@pytest.mark.slow
async def test_unusable_answers_are_asked_again_then_end_in_a_model_error() -> None:
    with server([(200, "not json"), (200, "[1, 2]"), ANSWER]) as llm:
        message, _ = await _complete(llm.base_url, retries=2)
    assert message["content"] == "hi" and len(llm.bodies) == 3
    with (server([(200, '{"choices": []}'), _completion("a string, not a message")]) as llm,
          pytest.raises(ModelError, match=r"failed 2 times: unusable response \(message")):
        await _complete(llm.base_url, retries=1)
    assert len(llm.bodies) == 2


async def test_no_server_is_a_model_error() -> None:
    port = unused_tcp_port()
    with pytest.raises(ModelError, match=r"failed once: APIConnectionError"):
        await _complete(f"http://127.0.0.1:{port}/v1", retries=0)


async def test_malformed_tool_calls_and_missing_usage_come_back_as_sent() -> None:
    calls = [{"id": "c1", "type": "function",
              "function": {"name": "take_off", "arguments": "{drone_id: oops"}},
             "not a call",
             {"type": "function", "function": {"name": "land", "arguments": {"drone_id": 1}}}]
    usages = [None, {"prompt_tokens": "many", "completion_tokens": -4}]
    with server([_completion({"role": "assistant", "content": None, "tool_calls": calls}, u)
                 for u in usages]) as llm:
        message, usage = await _complete(llm.base_url)
        _, odd_usage = await _complete(llm.base_url)
    assert message["tool_calls"] == calls and message["content"] is None
    assert usage == odd_usage == {"prompt": 0, "completion": 0}


@pytest.mark.parametrize(("config", "error"), [
    ({"model": ""}, "no model: pass --model or set OPENAI_MODEL"),
    ({"retries": -1}, "retries must be 0 or more, got -1"),
    ({"timeout_s": 0.0}, "timeout_s must be positive, got 0.0"),
    ({"max_completion_tokens": 0}, "max_completion_tokens must be at least 1, got 0"),
])
def test_bad_settings_are_refused_by_name(config: dict[str, Any], error: str,
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("OPENAI_MODEL", raising=False)
    settings = {"base_url": "http://127.0.0.1:9/v1", "model": "m", **config}
    with pytest.raises(ValueError, match=f"^{error}$".replace("(", r"\(").replace(")", r"\)")):
        OpenAIChatModel(ModelConfig(**settings))


# --------------------------------------------------------------- back into the conversation
def test_a_malformed_assistant_message_goes_back_well_formed() -> None:
    message = {"role": "assistant", "content": {"thought": 1}, "tool_calls": [
        "not a call",
        {"function": {"name": "land", "arguments": {"drone_id": "d1"}}},
        {"id": "c9", "type": "function", "function": {"name": "take_off", "arguments": "{bad"}}]}
    calls = parse_tool_calls(message)
    assert assistant_message(message, calls) == {
        "role": "assistant", "content": '{"thought": 1}', "tool_calls": [
            {"id": "call_0", "type": "function",
             "function": {"name": "unnamed", "arguments": "null"}},
            {"id": "call_1", "type": "function",
             "function": {"name": "land", "arguments": '{"drone_id": "d1"}'}},
            {"id": "c9", "type": "function",
             "function": {"name": "take_off", "arguments": "{bad"}}]}
    # The tool results answer exactly these ids.
    assert [c.id for c in calls] == ["call_0", "call_1", "c9"]
    assert assistant_message({"content": None}, []) == {"role": "assistant", "content": ""}
